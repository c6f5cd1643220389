"""The drivers: a problem, its events and the assembly of the result.

Each module is a thin driver over :func:`impactcont.core.driver.follow`: branches
(:mod:`.branch`, :mod:`.multi_branch`), codim-1 curves (:mod:`.curves`,
:mod:`.multi_curves`), branch switching and cascades (:mod:`.switching`) and
stability maps (:mod:`.maps`, the family sweep :mod:`.family_maps`). The public names
are re-exported by :mod:`impactcont`.
"""
