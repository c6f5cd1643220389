"""The compiled kernel: functions of floats and arrays, compiled by numba (``cache=True``).

The bottom layer of the package: it imports nothing of impactcont's.

- :mod:`.closed_form`: the N-1 motion of the paper in closed form (eq. 12-15, 25), its
  flights, roots, contact search and multipliers;
- :mod:`.general`: the same motion for any damping matrix C (first-order complex modes);
- :mod:`.shooting`: N-p motions by shooting (residual, exact Jacobian, G, contact checks);
- :mod:`.sweep`: stability maps of N-p motions (a breadth-first sweep of Newton solves).
"""
