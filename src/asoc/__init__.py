"""asoc: approximate stochastic optimal control.

The reproducible companion to M. Dolgov, "Approximate Stochastic Optimal Control of
Smooth Nonlinear Systems and Piecewise Linear Systems", PhD thesis, KIT, 2017.

Subpackages
-----------
mjls    Chapter 3: Markov jump linear systems without mode observation.
belief  Section 2.5: belief-space trajectory optimisation (statistical Taylor expansion).
gp      Section 2.6: Gaussian process regression over probability distributions.
stats   Bootstrap confidence intervals used by the Monte Carlo comparisons.
result  The common base of iterative results (converged, status, message).
validation  Argument checks shared by the subpackages.

The companion's tooling (recording values, the ledger, the book) is the separate package
``asoc_companion``; nothing in ``asoc`` imports it.
"""

__all__ = ["__version__"]

__version__ = "0.1.0"
