"""strug-manip: robots acting under model uncertainty.

Domains (toy POMDPs, and the Fetch manipulation tasks), the experiment runner, and the
``strug`` command line. The solvers live in the numpy-only ``planners`` package.
"""

__version__ = "0.1.0"
