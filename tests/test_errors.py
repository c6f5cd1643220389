"""The exception and warning types (:mod:`impactcont.errors`): the hierarchy the module
documents, so that ``except ValueError`` catches bad input and one warnings filter on
:class:`~impactcont.errors.IllConditionedWarning` catches every accuracy warning; and the
messages of the errors the package raises with them."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import impactcont as ic
from impactcont import errors

ACCURACY_WARNINGS = (errors.NearResonanceWarning, errors.NearFoldWarning,
                     errors.LowImpactVelocityWarning)


def test_every_name_of_all_is_exported_by_the_package() -> None:
    for name in errors.__all__:
        assert getattr(ic, name) is getattr(errors, name)


@pytest.mark.parametrize(("cls", "bases"), [
    (errors.ImpactcontError, (Exception,)),
    (errors.ParameterError, (errors.ImpactcontError, ValueError)),
    (errors.ResonanceError, (errors.ParameterError, errors.ImpactcontError, ValueError)),
    (errors.NoPeriodicMotionError, (errors.ImpactcontError, ValueError)),
])
def test_the_errors_are_caught_as_value_errors_and_as_impactcont_errors(cls, bases) -> None:
    for base in bases:
        assert issubclass(cls, base)
        with pytest.raises(base, match="the message"):
            raise cls("the message")


def test_an_impactcont_error_is_no_value_error_and_resonance_no_missing_motion() -> None:
    assert not issubclass(errors.ImpactcontError, ValueError)
    assert not issubclass(errors.NoPeriodicMotionError, errors.ParameterError)
    assert not issubclass(errors.ResonanceError, errors.NoPeriodicMotionError)


@pytest.mark.parametrize("cls", ACCURACY_WARNINGS)
def test_one_filter_turns_every_accuracy_warning_into_an_error(cls) -> None:
    assert issubclass(cls, errors.IllConditionedWarning)
    assert issubclass(cls, RuntimeWarning)
    with warnings.catch_warnings():
        warnings.simplefilter("error", errors.IllConditionedWarning)
        with pytest.raises(cls, match="inexact"):
            warnings.warn("inexact", cls, stacklevel=1)


def test_the_unresolved_motion_warning_is_no_accuracy_warning() -> None:
    """A capped search grid may miss a contact: not a rounding error, so the accuracy
    filter leaves it a warning."""
    assert issubclass(errors.UnresolvedMotionWarning, RuntimeWarning)
    assert not issubclass(errors.UnresolvedMotionWarning, errors.IllConditionedWarning)
    with warnings.catch_warnings():
        warnings.simplefilter("error", errors.IllConditionedWarning)
        with pytest.warns(errors.UnresolvedMotionWarning):
            warnings.warn("capped", errors.UnresolvedMotionWarning, stacklevel=1)


def test_bad_input_raises_a_parameter_error_naming_argument_and_value(paper) -> None:
    with pytest.raises(errors.ParameterError, match=r"osc must be an ImpactOscillator; got 3"):
        ic.periodic_orbits(3, N=1)
    with pytest.raises(ValueError, match=r"osc must be an ImpactOscillator"):
        ic.periodic_orbits("paper", N=1)


def test_an_exact_resonance_raises_a_resonance_error_naming_omega_and_the_mode() -> None:
    """Two equal masses with a damper between them: the symmetric mode (omega_1 = 1) is
    undamped, so its forced response at omega = 1 does not exist (eq. 6)."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[2.0, -1.0], [-1.0, 2.0]],
                              C=[[0.2, -0.2], [-0.2, 0.2]], F=[1.0, 0.0], R=0.6, b=0.1,
                              omega=1.0)
    with pytest.raises(errors.ResonanceError, match=r"omega=1\.0 .*natural frequency") as info:
        ic.periodic_orbits(osc, N=1)
    assert isinstance(info.value, ValueError)
