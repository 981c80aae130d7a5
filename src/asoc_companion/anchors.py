"""Links from a ledger row to the notebook section that computes it: the heading above the code
cell that records a value, and the HTML id Sphinx gives that heading.
"""

import json
import re

from docutils.nodes import make_id

__all__ = ["heading_anchor", "section_links"]


def heading_anchor(heading: str) -> str:
    """The HTML id Sphinx gives a Markdown heading (docutils ``make_id`` of its text).

    Examples
    --------
    >>> heading_anchor("## Sec. 3.5: the $T_1$ `chain`")
    'sec-3-5-the-t-1-chain'
    """
    text = re.sub(r"^#+\s*", "", heading.strip())
    text = re.sub(r"[`*]", "", text).replace("$", "")
    return make_id(text)


def _records(source: str, name: str) -> bool:
    if f'"{name}"' in source or f"'{name}'" in source:
        return True
    for pattern in re.findall(r'record\(\s*f"([^"]+)"', source):
        if re.fullmatch(re.sub(r"\\\{[^}]*\\\}", ".+", re.escape(pattern)), name):
            return True
    return any(
        name.startswith(prefix) for prefix in re.findall(r'record\(\s*"([^"]+_)"\s*\+', source)
    )


def section_links(notebook_path, names) -> dict:
    """``{name: "<page>.html#<id>"}``: the heading above the code cell that records each name.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> cells = [{"cell_type": "markdown", "source": "## Spectral radius"},
    ...          {"cell_type": "code", "source": ["rho = 0.25; ", 'record("rho", rho)']}]
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = pathlib.Path(folder) / "demo.ipynb"
    ...     _ = path.write_text(json.dumps({"cells": cells, "metadata": {}}))
    ...     print(section_links(path, ["rho", "gain"]))
    {'rho': 'demo.html#spectral-radius', 'gain': 'demo.html'}
    """
    cells = json.loads(notebook_path.read_text())["cells"]
    page = notebook_path.stem + ".html"
    links, heading = {}, None
    for cell in cells:
        source = "".join(cell["source"])
        if cell["cell_type"] == "markdown":
            sub = [line for line in source.splitlines() if re.match(r"#{2,6}\s", line)]
            heading = sub[-1] if sub else heading
        elif cell["cell_type"] == "code":
            for name in names:
                if name not in links and _records(source, name):
                    links[name] = page + ("#" + heading_anchor(heading) if heading else "")
    return {name: links.get(name, page) for name in names}
