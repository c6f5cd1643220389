"""Shared fixtures: the paper's example system (section 4) and a few others."""

from __future__ import annotations

import os
import signal
import warnings

# one BLAS thread: the closed form does many tiny solves, which threads only slow down
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
import pytest

from impactcont import ImpactOscillator

# shared fixtures: a made-up branch dataset (osc, branch; a module's own fixture of the
# same name wins) and the paper's period-doubling cascade at b = 0 (paper_b0, branch_n1,
# branch_22, branch_44)
pytest_plugins = ["tests._made_up_branch", "tests._multi_impact_cases"]


@pytest.fixture(autouse=True)
def _sigint_kept(request: pytest.FixtureRequest):
    """Each test leaves Ctrl-C (SIGINT) as it found it, or is named in a warning and its
    change undone: a SIGINT left ignored in this process is inherited by every child a
    later test starts, whose Ctrl-C then does nothing. (The two Ctrl-C tests of children
    that failed in full runs had inherited it from the shell that started pytest in the
    background, not from a test: their children now reset it, :mod:`tests._ctrl_c`.)"""
    before = signal.getsignal(signal.SIGINT)
    yield
    after = signal.getsignal(signal.SIGINT)
    if after is not before:
        signal.signal(signal.SIGINT, before)
        warnings.warn(f"{request.node.nodeid} left SIGINT set to {after!r} (restored)",
                      RuntimeWarning, stacklevel=1)


@pytest.fixture
def paper() -> ImpactOscillator:
    """Cao & Shu section 4: n = 2, M = I, K = [[1,-1],[-1,2]], eta = 0.1, R = 0.6, F = [1, 0]."""
    return ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                            b=0.6, omega=1.0, eta=0.1)


def _chain(n: int, **params) -> ImpactOscillator:
    """A chain of n unequal masses and springs, forced on mass 1 and mass n."""
    rng = np.random.default_rng(n)
    masses = 1.0 + 0.5 * rng.random(n)
    springs = 1.0 + rng.random(n)
    F = np.zeros(n)
    F[0] = 1.0
    F[-1] = 0.3
    defaults = {"F": F, "R": 0.7, "b": 0.1, "omega": 1.1, "eta": 0.05}
    if "alpha" in params or "beta" in params:
        del defaults["eta"]
    defaults.update(params)
    return ImpactOscillator.chain(masses=masses, springs=springs, **defaults)


@pytest.fixture
def make_chain():
    """Factory ``make_chain(n, **params)`` of test chains."""
    return _chain
