"""Progress bars for long computations: shown on an interactive terminal, kept out of
executed notebooks (papermill records stderr into the notebook, and the book would show
every refresh of the bar).
"""

from tqdm import tqdm

__all__ = ["progress_bar"]


def progress_bar(iterable=None, enabled=True, **kwargs):
    """``tqdm(iterable, **kwargs)`` when ``enabled`` and stderr is a terminal, else silent.

    Examples
    --------
    The bar (on a terminal only) goes to stderr; the items pass through unchanged:

    >>> list(progress_bar(range(3), desc="runs"))
    [0, 1, 2]
    """
    return tqdm(iterable, disable=None if enabled else True, **kwargs)
