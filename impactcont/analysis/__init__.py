"""The drivers: a problem, its events and the assembly of the result.

Each module is a thin driver over :func:`impactcont.core.driver.follow`, one for every
motion (the N-1 closed form and shooting are two evaluators of the same problem):
branches (:mod:`.branch`), codim-1 curves (:mod:`.curves`), branch switching and
cascades (:mod:`.switching`) and stability maps (:mod:`.maps`, the family sweep
:mod:`.family_maps`). The public names are re-exported by :mod:`impactcont`.
"""
