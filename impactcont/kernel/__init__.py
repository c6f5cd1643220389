"""The compiled kernel: functions of floats and arrays, compiled by numba (``cache=True``).

The bottom layer of the package: it imports nothing of impactcont's. One module per
concern:

- :mod:`.arrays`: the modal arrays of eq. (5)-(7) the entry points take
  (:class:`~impactcont.kernel.arrays.ModalArrays`, built and checked in one place);
- :mod:`.flights`: a flight in modal form, the free transfer ``W_i(t)`` of eq. (9) and
  the forced response of eq. (7);
- :mod:`.roots`: the roots of eq. (15), impact phases and velocities;
- :mod:`.contact`: the interior-contact check of eq. (16), the highest maximum of x1;
- :mod:`.stability`: stability of G (eq. 25) without eigenvalues (Schur-Cohn on its
  characteristic polynomial) and its multipliers;
- :mod:`.closed_form`: the N-1 motion of the paper in closed form (eq. 12-15, 22-25)
  assembled from the above;
- :mod:`.general`: the same motion for any damping matrix C (first-order complex modes);
- :mod:`.shooting`: N-p motions by shooting (residual, exact Jacobian, G, contact checks);
- :mod:`.half_map`: a product of flight Jacobians (eq. 25) and its exact derivatives;
- :mod:`.sweep`: stability maps of N-p motions (a breadth-first sweep of Newton solves).
"""
