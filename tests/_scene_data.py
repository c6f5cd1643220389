"""Small scenes shared by the scene and CLI tests (fast: a few seconds in all)."""

from __future__ import annotations

from pathlib import Path

OSCILLATOR = """
[oscillator]
K = [[1.0, -1.0], [-1.0, 2.0]]
F = [1.0, 0.0]
R = 0.6
eta = 0.1
b = 0.6
omega = 1.0
"""

#: One entry of every section and a plot of every kind, on narrow ranges.
SMALL_SCENE = f'''title = "small"
{OSCILLATOR}
[output]
dpi = 40

[[orbits]]
name = "o1"

[[branches]]
name = "br"
b = 0.5
bounds = [1.1, 1.3]
ds_max = 0.05

[[robust]]
name = "rb"
vary = {{ b = [0.5, 0.7] }}
samples = 5

[[simulations]]
name = "sim"
periods = 3.5
trajectory = true

[[plots]]
name = "bif"
kind = "bifurcation_diagram"

[[plots]]
name = "mult"
kind = "multipliers"

[[plots]]
name = "orb"
kind = "orbits"

[[plots]]
name = "rob"
kind = "robust"

[[plots]]
name = "simp"
kind = "simulation"
'''

#: Orbits only: the cheapest scene that writes something.
ORBITS_SCENE = f'''title = "orbits only"
{OSCILLATOR}
[[orbits]]
name = "paper"

[[orbits]]
name = "fig3"
N = 2
b = 0.0
omega = 2.4
'''


def write(directory: Path, text: str, name: str = "scene.toml") -> Path:
    """Write a scene file and return its path."""
    path = directory / name
    path.write_text(text, encoding="utf-8")
    return path
