"""progress= on the long calls: callbacks, the bar, the log line a minute (impactcont.progress)."""

from __future__ import annotations

import logging
import re
import subprocess
import sys

import numpy as np
import pytest

import impactcont as ic
import impactcont.progress as progress_module
from impactcont.analysis.curves import multi_impact_curve
from impactcont.progress import Progress, Reporter, check_progress


@pytest.fixture(scope="module")
def system() -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                               b=0.0, omega=1.0, eta=0.1)


@pytest.fixture(scope="module")
def branch(system):
    return ic.continuation(system, 1, "omega", (1.4, 2.0), components="start", progress=False)


def _check(records: list[Progress], what: str, total: int | None = None,
           parameter: str | None = None, bounds: tuple[float, float] | None = None) -> None:
    assert records, "the callback was never called"
    done = [r.done for r in records]
    assert np.all(np.diff(done) > 0), done
    assert all(r.what.startswith(what) for r in records)
    assert all(r.total == total for r in records)
    assert all(r.parameter == parameter for r in records)
    elapsed = [r.elapsed for r in records]
    assert elapsed == sorted(elapsed) and elapsed[0] >= 0
    if total is not None:
        assert done[-1] == total
    if bounds is not None:
        values = np.array([r.value for r in records])
        assert np.all((values >= bounds[0] - 1e-12) & (values <= bounds[1] + 1e-12))


def test_continuation_calls_back_at_every_point(system):
    records: list[Progress] = []
    br = ic.continuation(system, 1, "omega", (1.4, 2.0), components="start",
                         progress=records.append)
    _check(records, "continuation in omega", parameter="omega", bounds=(1.4, 2.0))
    # every accepted point of both directions (the shared start once in each)
    assert records[-1].done == br.sizes["point"] + 1


def test_curve_calls_back(system, branch):
    records: list[Progress] = []
    ic.curve(system, None, "PD", start=branch, bounds={"omega": (1.4, 2.0), "b": (-0.1, 0.1)},
             max_points=6, progress=records.append)
    _check(records, "PD curve in (omega, b)", parameter="b", bounds=(-0.1, 0.1))


def test_map_calls_back_with_its_total(system):
    records: list[Progress] = []
    ic.stability_map(system, [1, 2], np.linspace(0.5, 3.0, 40), np.linspace(-0.5, 0.5, 30),
                     omega_block=8, progress=records.append)
    _check(records, "stability map", total=2 * 40 * 30)
    assert len(records) == 2 * 5  # one record per task


def test_robust_stability_calls_back_with_its_total(system):
    records: list[Progress] = []
    ic.robust_stability(system.replace(b=0.6), 1, vary={"b": (0.2, 1.0)}, samples=9,
                        progress=records.append)
    _check(records, "robust stability", total=9 + 16)  # grid points, then the entries of G


def test_multi_impact_drivers_call_back(branch):
    records: list[Progress] = []
    child = ic.period_doubling_switch(branch, bounds=(1.6, 2.0), max_points=12,
                                      progress=records.append)
    _check(records, "continuation of 2-2 motions in omega", parameter="omega",
           bounds=(1.6, 2.0))
    records.clear()
    np_branch = ic.multi_impact_continuation(ic.special_orbit(branch, "PD"), "omega",
                                             (1.6, 1.8), max_points=8,
                                             progress=records.append)
    _check(records, "continuation of 1-1 motions in omega", parameter="omega",
           bounds=(1.6, 1.8))
    records.clear()
    multi_impact_curve(np_branch, "PD", parameter="b",
                       bounds={"omega": (1.6, 1.8), "b": (-0.05, 0.05)}, max_points=4,
                       progress=records.append)
    _check(records, "PD curve of 1-1 motions in (omega, b)", parameter="b",
           bounds=(-0.05, 0.05))
    assert child.sizes["point"] > 1


def test_cascade_counts_the_points_of_all_its_branches(branch):
    records: list[Progress] = []
    cascade = ic.period_doubling_cascade(branch, max_doublings=2, max_points=25,
                                         progress=records.append)
    _check(records, "period-doubling cascade in omega", parameter="omega")
    assert records[-1].done >= sum(b.sizes["point"] for b in cascade.branches[1:])


def test_bar_silent_when_stderr_is_not_a_terminal(system, capsys):
    ic.continuation(system, 1, "omega", (1.4, 2.0), components="start")
    ic.stability_map(system, 1, np.linspace(0.5, 3.0, 20), np.linspace(-0.5, 0.5, 10))
    assert capsys.readouterr().err == ""
    # asked for: a bar even on a pipe
    ic.continuation(system, 1, "omega", (1.4, 2.0), components="start", progress=True)
    assert "continuation in omega" in capsys.readouterr().err


def test_bar_after_a_delay_on_a_terminal(monkeypatch):
    monkeypatch.setattr(progress_module, "_stderr_is_terminal", lambda: True)
    with Reporter("work", None) as rep:
        assert rep._bar is not None and rep._bar.delay == progress_module.BAR_DELAY
    with Reporter("work", False) as rep:
        assert rep._bar is None


class _FakeClock:
    """Seconds that pass `step` at every reading."""

    def __init__(self, step: float) -> None:
        self.now, self.step = 1000.0, step

    def __call__(self) -> float:
        self.now += self.step
        return self.now


def test_one_log_line_a_minute_at_most(system, monkeypatch, caplog):
    clock = _FakeClock(7.0)  # every reading 7 s later: a 'long' continuation
    monkeypatch.setattr(progress_module, "clock", clock)
    caplog.set_level(logging.INFO, logger="impactcont.progress")
    ic.continuation(system, 1, "omega", (1.4, 2.0), components="start", progress=False)
    lines = [r.getMessage() for r in caplog.records if r.name == "impactcont.progress"]
    minutes = (clock.now - 1000.0) / 60.0
    assert 1 <= len(lines) <= minutes + 1
    assert all(line.startswith("continuation in omega: ") and " points, omega = " in line
               and line.endswith(" s") for line in lines)


def test_log_line_format_with_a_fake_clock(monkeypatch, caplog):
    clock = _FakeClock(0.0)
    monkeypatch.setattr(progress_module, "clock", clock)
    caplog.set_level(logging.INFO, logger="impactcont.progress")
    rep = Reporter("continuation in omega", False, parameter="omega")
    rep.advance(1233, 2.2)
    assert not caplog.records  # no time has passed
    clock.now += 61.0
    rep.advance(1, 2.31)
    clock.now += 30.0
    rep.advance(1, 2.4)  # within the minute after the line: none
    assert [r.getMessage() for r in caplog.records] == [
        "continuation in omega: 1234 points, omega = 2.31, 61 s"]
    mapped = Reporter("stability map", False, total=1000)
    clock.now += 61.0
    mapped.advance(250)
    assert caplog.records[-1].getMessage() == "stability map: 250 of 1000 points (25 %), 61 s"


@pytest.mark.parametrize("bad", ["yes", 1, object()])
def test_bad_progress_is_refused(system, bad):
    with pytest.raises(TypeError, match="progress must be None"):
        ic.continuation(system, 1, "omega", (1.4, 2.0), components="start", progress=bad)
    with pytest.raises(TypeError, match="progress must be None"):
        ic.stability_map(system, 1, [1.0, 2.0], [0.0, 0.1], progress=bad)


@pytest.mark.parametrize("callback", [lambda: None, lambda a, b: None])
def test_a_callable_that_cannot_take_the_record_is_refused_by_name(callback) -> None:
    with pytest.raises(TypeError, match=r"progress must be a callable taking one Progress "
                                        r"record.*got <function") as info:
        check_progress(callback)
    assert "lambda" in str(info.value)
    with pytest.raises(TypeError, match="progress must be a callable taking one Progress"):
        Reporter("work", callback)


def test_callables_that_take_the_record_pass() -> None:
    def keyword_default(record, extra=1):
        return None

    for ok in (print, lambda *args: None, keyword_default, [].append, None, True, False):
        assert check_progress(ok) is ok


# -- log records above the bar --------------------------------------------------------------------
def _glued(err: str, message: str) -> list[str]:
    """The pieces of `err` (split at line ends and carriage returns) that hold `message`
    with other text: a message glued to a bar line."""
    return [piece for piece in re.split(r"[\r\n]", err) if message in piece and piece != message]


def test_a_record_logged_under_a_bar_gets_a_line_of_its_own(capsys):
    handler = logging.StreamHandler(sys.stderr)  # the user's console handler
    handler.setFormatter(logging.Formatter("%(levelname)s %(message)s"))
    package = logging.getLogger("impactcont")
    package.addHandler(handler)
    try:
        with Reporter("continuation in omega", True, parameter="omega") as rep:
            rep.advance(3, 1.5)
            logging.getLogger("impactcont.analysis.maps").warning("written to a temporary file")
            rep.advance(1, 1.6)
        assert handler.stream is sys.stderr  # given back when the bar closes
        logging.getLogger("impactcont.analysis.maps").warning("after the bar")
    finally:
        package.removeHandler(handler)
    err = capsys.readouterr().err
    assert "continuation in omega: " in err
    assert "\nWARNING written to a temporary file\n" in err.replace("\r", "\n")
    assert _glued(err, "WARNING written to a temporary file") == []
    assert err.endswith("WARNING after the bar\n")


def test_a_warning_logged_during_a_continuation_does_not_break_its_bar(system, capsys):
    handler = logging.StreamHandler(sys.stderr)
    package = logging.getLogger("impactcont")
    package.addHandler(handler)

    def noisy(orbit):  # a user monitor that logs, evaluated while the bar is shown
        logging.getLogger("impactcont.user").warning("monitor says hello")
        return 0.0

    try:
        ic.continuation(system, 1, "omega", (1.4, 2.0), components="start", progress=True,
                        monitors={"noisy": noisy})
    finally:
        package.removeHandler(handler)
    err = capsys.readouterr().err
    assert "continuation in omega" in err and "monitor says hello" in err
    assert _glued(err, "monitor says hello") == []


def test_without_a_handler_the_last_resort_writes_above_the_bar():
    script = ("import logging\n"
              "from impactcont.progress import Reporter\n"
              "with Reporter('work', True) as rep:\n"
              "    rep.advance(2)\n"
              "    logging.getLogger('impactcont.x').warning('last resort speaks')\n"
              "    rep.advance(1)\n"
              "assert type(logging.lastResort).__name__ == '_StderrHandler'\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    assert "last resort speaks" in done.stderr
    assert _glued(done.stderr, "last resort speaks") == []


def test_a_record_before_a_delayed_bar_shows_does_not_draw_it(monkeypatch, capsys):
    monkeypatch.setattr(progress_module, "_stderr_is_terminal", lambda: True)
    handler = logging.StreamHandler(sys.stderr)
    package = logging.getLogger("impactcont")
    package.addHandler(handler)
    try:
        with Reporter("work", None) as rep:  # the bar would show after BAR_DELAY s
            rep.advance(1)
            logging.getLogger("impactcont.x").warning("early message")
            rep.advance(1)
    finally:
        package.removeHandler(handler)
    assert capsys.readouterr().err == "early message\n"  # no bar drawn, no stray \r
