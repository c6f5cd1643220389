"""``python -m impactcont``: the ``impactcont`` command line (see :mod:`impactcont.cli`)."""

from impactcont.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
