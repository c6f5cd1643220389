"""Progress of long work: a tqdm bar, a callback for programs, a log line per minute.

Every long call of impactcont (:func:`~impactcont.continuation`,
:func:`~impactcont.curve`, :func:`~impactcont.stability_map`,
:func:`~impactcont.multi_impact_continuation`, :func:`~impactcont.multi_impact_curve`,
:func:`~impactcont.period_doubling_cascade`, :func:`~impactcont.robust_stability`)
takes ``progress=``:

- ``None`` (default): a tqdm bar on stderr when stderr is a terminal, shown once the
  work has taken :data:`BAR_DELAY` seconds (short calls stay quiet); nothing otherwise;
- ``True``: a bar on stderr at once, terminal or not; ``False``: no bar;
- a callable: called with a :class:`Progress` record after every step of the work
  (a continuation point, a block of a map, an evaluation), and no bar.

Whatever the option, a call that works for more than a minute writes one INFO line per
minute at most on the ``impactcont.progress`` logger, e.g. ``continuation in omega:
1234 points, omega = 2.31, 61 s``. Continuation-type work has no known total (the
points and the parameter value are shown); maps and robust stability have one.

Drivers open a :class:`Reporter` with :func:`reporter` and call :meth:`Reporter.advance`
(or pass :meth:`Reporter.point` as the core's ``on_point``); a driver that runs another
one passes its reporter on, so nested work counts in one bar.

While a bar is shown, the records of the package's loggers go above it
(:func:`logging_through_bar`): a warning logged mid-run gets a line of its own and the bar
is drawn again below it.

Ctrl-C (:class:`KeyboardInterrupt`) during a call run in :func:`interruptible` is taken
once: the code that computes catches it, asks :func:`take_interrupt`, and the call returns
what it has computed, marked as interrupted. A second Ctrl-C aborts the call as usual.
"""

from __future__ import annotations

import contextlib
import contextvars
import inspect
import logging
import math
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from types import TracebackType
from typing import Any, TypeVar

__all__ = ["BAR_DELAY", "LOG_INTERVAL", "Interruption", "NothingComputed", "Progress",
           "ProgressOption", "Reporter", "check_progress", "interrupted", "interruptible",
           "logging_through_bar", "reporter", "take_interrupt", "until_interrupted"]

log = logging.getLogger(__name__)

LOG_INTERVAL = 60.0
"""Seconds of work between two progress lines in the log, at least."""
BAR_DELAY = 2.0
"""Seconds before the default bar (``progress=None`` on a terminal) appears."""

clock: Callable[[], float] = time.monotonic
"""The clock of the reporters made from now on (replaced by a fake one in tests)."""


@dataclass(frozen=True)
class Progress:
    """Where a long call is: the record a ``progress=`` callable receives.

    Attributes
    ----------
    what : str
        The work, e.g. ``"continuation in omega"`` or ``"stability map"``.
    done : int
        Units of work done so far (points, map points, evaluations); increases.
    total : int or None
        Units of the whole work when known (maps, robust stability), else None.
    parameter : str or None
        The continued parameter, None for work without one.
    value : float or None
        Its value at the last point, None when there is none.
    elapsed : float
        Seconds since the work started.
    """

    what: str
    done: int
    total: int | None
    parameter: str | None
    value: float | None
    elapsed: float


ProgressOption = bool | Callable[[Progress], Any] | None
"""What ``progress=`` accepts: None (a bar on a terminal), True, False or a callable."""


def check_progress(progress: Any, argument: str = "progress") -> Any:
    """The ``progress=`` option, checked before any work: None, a bool or a callable that
    takes one :class:`Progress` record (its signature is read; one it cannot be read from,
    a builtin's, is taken on trust).

    Returns
    -------
    object
        `progress`, unchanged.

    Raises
    ------
    TypeError
        Naming `argument`, the value and what is allowed.
    """
    if progress is None or isinstance(progress, bool):
        return progress
    if not callable(progress):
        raise TypeError(f"{argument} must be None (a bar when stderr is a terminal), True, "
                        f"False or a callable taking a Progress record; got {progress!r}")
    try:
        signature = inspect.signature(progress)
    except (TypeError, ValueError):  # a builtin without a signature
        return progress
    try:
        signature.bind(None)
    except TypeError as exc:
        raise TypeError(f"{argument} must be a callable taking one Progress record (called as "
                        f"{argument}(record) at every step); got {progress!r} with signature "
                        f"{signature} ({exc})") from None
    return progress


def _stderr_is_terminal() -> bool:
    isatty = getattr(sys.stderr, "isatty", None)
    try:
        return bool(isatty and isatty())
    except (ValueError, OSError):  # a closed or detached stream
        return False


class Reporter:
    """The progress of one long call: counts its work, draws, calls back and logs.

    Parameters
    ----------
    what : str
        The work, in words (the bar's title and the start of the log line).
    progress : None, bool or callable
        The ``progress=`` option of the driver (see the module docstring).
    total : int, optional
        Units of the whole work, when known.
    parameter : str, optional
        The continued parameter (shown with its value).
    unit : str
        The unit of work, plural (``"points"``).

    Raises
    ------
    TypeError
        `progress` is not None, True, False or a callable taking one record
        (:func:`check_progress`).
    """

    def __init__(self, what: str, progress: ProgressOption = None, *, total: int | None = None,
                 parameter: str | None = None, unit: str = "points") -> None:
        check_progress(progress)
        self.what, self.total, self.parameter, self.unit = what, total, parameter, unit
        self.done = 0
        self.value: float | None = None
        self._clock = clock
        self.start = self._clock()
        self._next_log = self.start + LOG_INTERVAL
        self._callback = progress if callable(progress) else None
        self._bar: Any = None
        self._logging = contextlib.ExitStack()
        if progress is True or (progress is None and _stderr_is_terminal()):
            self._bar = self._open_bar(delay=0.0 if progress is True else BAR_DELAY)
            if self._bar is not None:
                self._logging.enter_context(logging_through_bar())

    def _open_bar(self, delay: float) -> Any:
        try:
            from tqdm import tqdm
        except ImportError:  # a dependency; a broken install still computes
            log.warning("tqdm is not installed: no progress bar for %s", self.what)
            return None
        return tqdm(total=self.total, desc=self.what, unit=f" {self.unit}", file=sys.stderr,
                    delay=delay, leave=False, dynamic_ncols=True)

    @property
    def elapsed(self) -> float:
        """Seconds since the work started."""
        return self._clock() - self.start

    def record(self) -> Progress:
        """The work done so far as a :class:`Progress` record."""
        return Progress(self.what, self.done, self.total, self.parameter, self.value,
                        self.elapsed)

    def advance(self, count: int = 1, value: float | None = None) -> None:
        """Count `count` more units of work, the last at parameter value `value`."""
        self.done += count
        if value is not None:
            self.value = value
        now = self._clock()
        if now >= self._next_log:
            self._next_log = now + LOG_INTERVAL
            log.info("%s", self.line(now - self.start))
        if self._bar is not None:
            if value is not None:
                self._bar.set_postfix_str(f"{self.parameter} = {value:.6g}", refresh=False)
            self._bar.update(count)
        if self._callback is not None:
            self._callback(Progress(self.what, self.done, self.total, self.parameter,
                                    self.value, now - self.start))

    def point(self, point: Any) -> None:
        """:meth:`advance` by one continuation point (the core's ``on_point``)."""
        self.advance(1, point.lam)

    def line(self, elapsed: float) -> str:
        """The log line: ``what: done [of total (pc %)] unit[, parameter = value], s``."""
        if self.total:
            count = (f"{self.done} of {self.total} {self.unit} "
                     f"({100.0 * self.done / self.total:.0f} %)")
        else:
            count = f"{self.done} {self.unit}"
        where = (f", {self.parameter} = {self.value:.6g}"
                 if self.parameter is not None and self.value is not None else "")
        return f"{self.what}: {count}{where}, {elapsed:.0f} s"

    def close(self) -> None:
        """Close the bar and give the log handlers their streams back (idempotent)."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None
        self._logging.close()

    def __enter__(self) -> Reporter:
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 trace: TracebackType | None) -> None:
        self.close()


class _Shared:
    """A reporter of an enclosing call, entered again by a nested driver: not closed."""

    def __init__(self, shared: Reporter) -> None:
        self.shared = shared

    def __enter__(self) -> Reporter:
        return self.shared

    def __exit__(self, *exc: object) -> None:
        return None


def reporter(progress: ProgressOption | Reporter, what: str, *, total: int | None = None,
             parameter: str | None = None, unit: str = "points") -> Reporter | _Shared:
    """The reporter of a driver call, to use as a context manager.

    Parameters
    ----------
    progress : None, bool, callable or Reporter
        The driver's ``progress=`` option; a :class:`Reporter` of an enclosing call is
        used as it is (and left open).
    what, total, parameter, unit
        See :class:`Reporter`.

    Returns
    -------
    context manager
        Entering it gives the :class:`Reporter`; leaving it closes the bar.

    Raises
    ------
    TypeError
        `progress` is not None, True, False, a callable or a Reporter.
    """
    if isinstance(progress, Reporter):
        return _Shared(progress)
    return Reporter(what, progress, total=total, parameter=parameter, unit=unit)


# -- log records above the bar ------------------------------------------------------------------
def _bar_shown() -> bool:
    """Whether a tqdm bar is on the screen (one delayed and not drawn yet is not)."""
    from tqdm import tqdm
    return any(not bar.disable and getattr(bar, "last_print_t", -math.inf)
               >= getattr(bar, "start_t", math.inf) + getattr(bar, "delay", 0.0)
               for bar in list(getattr(tqdm, "_instances", ())))


class _AboveBar:
    """A console stream whose writes go through ``tqdm.write`` while a bar is shown: above
    the bars, which are drawn again below the text."""

    def __init__(self, stream: Any) -> None:
        self.stream = stream

    def write(self, text: str) -> int:
        from tqdm import tqdm
        if _bar_shown():
            tqdm.write(text, file=self.stream, end="")
        else:  # tqdm.write would draw a delayed bar before its time
            self.stream.write(text)
        return len(text)

    def flush(self) -> None:
        self.stream.flush()

    def __getattr__(self, name: str) -> Any:  # isatty, encoding, fileno, ...
        return getattr(self.stream, name)


def _console(stream: Any) -> bool:
    return any(stream is s and s is not None
               for s in (sys.stderr, sys.stdout, sys.__stderr__, sys.__stdout__))


def _package_loggers() -> list[logging.Logger]:
    """The loggers whose handlers see the package's records: ``impactcont`` and those below
    it that exist, then the ancestors a record propagates to (the root last)."""
    loggers = [logging.getLogger("impactcont")]
    loggers += [logger for name, logger in list(logging.Logger.manager.loggerDict.items())
                if name.startswith("impactcont.") and isinstance(logger, logging.Logger)]
    parent = loggers[0].parent
    while parent is not None:
        loggers.append(parent)
        parent = parent.parent
    return loggers


@contextlib.contextmanager
def logging_through_bar() -> Iterator[None]:
    """While it is entered, the package's log records are written above the tqdm bars.

    The console handlers (a :class:`logging.StreamHandler` on stderr or stdout) of the
    ``impactcont`` loggers and of the loggers their records propagate to (the root
    logger's, as :func:`logging.basicConfig` sets it up) write through ``tqdm.write``,
    so a message logged mid-run is a line of its own and the bar is drawn again below it;
    without any handler, Python's last-resort handler (warnings and errors on stderr)
    does the same. Their levels, formatters and filters are kept, no handler is added,
    and every stream is given back when the context exits. A
    :class:`~impactcont.progress.Reporter` enters it while its bar is shown; a driver
    drawing a bar of its own can enter it around its work.

    Without tqdm it does nothing.
    """
    try:
        import tqdm  # noqa: F401
    except ImportError:
        yield
        return
    swapped: list[tuple[logging.StreamHandler, Any]] = []
    last_resort = logging.lastResort
    try:
        for logger in _package_loggers():
            for handler in logger.handlers:
                if (isinstance(handler, logging.StreamHandler)
                        and not isinstance(handler, logging.FileHandler)
                        and _console(handler.stream)):
                    swapped.append((handler, handler.stream))
                    handler.stream = _AboveBar(handler.stream)
        if last_resort is not None and not isinstance(last_resort, _LastResortAboveBar):
            logging.lastResort = _LastResortAboveBar(last_resort.level)
        yield
    finally:
        logging.lastResort = last_resort
        for handler, stream in reversed(swapped):
            handler.stream = stream


class _LastResortAboveBar(logging.StreamHandler):
    """Python's last-resort handler (used when no handler is configured), above the bar."""

    def __init__(self, level: int) -> None:
        super().__init__()
        self.setLevel(level)

    @property  # type: ignore[override]
    def stream(self) -> Any:
        return _AboveBar(sys.stderr)

    @stream.setter
    def stream(self, value: Any) -> None:  # set by StreamHandler.__init__: stderr is read
        pass


# -- Ctrl-C during a call ---------------------------------------------------------------------
class NothingComputed(KeyboardInterrupt):
    """Ctrl-C taken before a driver's first point: nothing to return, the call is aborted.

    A driver that runs others (a cascade, an extension) catches it and returns what the
    ones before computed.
    """


class Interruption:
    """The interrupt state of one library call (see :func:`interruptible`).

    Attributes
    ----------
    what : str
        The call, in words (``"continuation in omega"``).
    where : str or None
        Where the first Ctrl-C was taken (``"continuation"``, ``"location"``, ...);
        None while the call has not been interrupted.
    """

    def __init__(self, what: str) -> None:
        self.what = what
        self.where: str | None = None

    @property
    def interrupted(self) -> bool:
        """Whether Ctrl-C has been taken during the call."""
        return self.where is not None


_CALL: contextvars.ContextVar[Interruption | None] = contextvars.ContextVar(
    "impactcont_interruption", default=None)


@contextlib.contextmanager
def interruptible(what: str) -> Iterator[Interruption]:
    """Run a library call whose first Ctrl-C returns the work done so far.

    Entered by the drivers (continuation, curves, branch switching): inside it, the code
    that computes catches :class:`KeyboardInterrupt` and calls :func:`take_interrupt`; the
    first interrupt is taken (the call finishes with what it has and returns it, marked
    as interrupted), a second one aborts as usual. A driver called by another one joins
    its caller's call: one interrupt for the whole.

    Parameters
    ----------
    what : str
        The call, in words, for the log.

    Yields
    ------
    Interruption
        The state of the call (the caller's, for a nested driver).
    """
    outer = _CALL.get()
    if outer is not None:
        yield outer
        return
    state = Interruption(what)
    token = _CALL.set(state)
    try:
        yield state
    finally:
        _CALL.reset(token)


def take_interrupt(where: str, message: str, *args: Any) -> bool:
    """In an ``except KeyboardInterrupt`` handler: whether the interrupt is taken.

    Parameters
    ----------
    where : str
        The phase interrupted (``"continuation"``, ``"location"``), kept in the state.
    message, *args
        What is kept, logged at WARNING on the ``impactcont.progress`` logger with
        ``"<what>: "`` before it and the hint that Ctrl-C again aborts after it.

    Returns
    -------
    bool
        True for the first interrupt inside :func:`interruptible`: the caller keeps what
        it computed and goes on to return it. False outside any call or for a second
        interrupt: the caller re-raises it.
    """
    state = _CALL.get()
    if state is None or state.interrupted:
        return False
    state.where = where
    log.warning("%s: " + message + "; Ctrl-C again to abort", state.what, *args)
    return True


def interrupted(where: str | None = None) -> bool:
    """Whether the current call has been interrupted (in phase `where`, when given)."""
    state = _CALL.get()
    return state is not None and state.interrupted and (where is None or state.where == where)


_T = TypeVar("_T")


def until_interrupted(work: Callable[[], _T], default: _T, where: str, message: str,
                      *args: Any) -> _T:
    """``work()``, or `default` when the first Ctrl-C of the call is taken during it.

    For a phase of a driver's work whose partial result is not kept (the location of the
    special points of one branch, say): the call goes on with `default` after the first
    interrupt, and skips the phase (returns `default` at once) once an interrupt has
    been taken in the same phase `where` before. A second interrupt is raised.

    Parameters
    ----------
    work : callable
        The phase, without arguments.
    default : object
        Its result when interrupted or skipped.
    where : str
        The phase's name (``"location"``).
    message, *args
        What is dropped, for the log (see :func:`take_interrupt`).
    """
    if interrupted(where):
        return default
    try:
        return work()
    except KeyboardInterrupt:
        if not take_interrupt(where, message, *args):
            raise
        return default
