"""The exact flow, closed-form periodic motions, G and robust stability (eq. 9-29)."""
