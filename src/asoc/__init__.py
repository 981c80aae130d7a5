"""asoc: approximate stochastic optimal control.

The reproducible companion to M. Dolgov, "Approximate Stochastic Optimal Control of
Smooth Nonlinear Systems and Piecewise Linear Systems", PhD thesis, KIT, 2017.

Subpackages
-----------
mjls    Chapter 3: Markov jump linear systems without mode observation.
belief  Section 2.5: belief-space trajectory optimisation (statistical Taylor expansion).
gp      Section 2.6: Gaussian process regression over probability distributions.
repro   Recording values, reference values, the ledger, figure style and saving.
"""

__version__ = "0.1.0"
