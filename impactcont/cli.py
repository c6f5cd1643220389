"""The ``impactcont`` command: run scenes, describe and draw their files, list problems.

::

    impactcont run SCENE.toml [--output DIR] [--set KEY=VALUE ...] [--check]
    impactcont plot FILE.nc [-o PNG] [--kind KIND] [--y VARIABLE] [--width INCHES]
    impactcont info FILE.nc
    impactcont list-problems

``run`` computes every section of the scene, the built-in ones and those of
problem plugins (entry-point group ``impactcont.problems``, see
``docs/plugins.md``); ``list-problems`` lists them with their scene section.

Also ``python -m impactcont``. Options ``-v`` (info; ``-vv`` debug) and
``-q`` (errors only) set the logging level, before or after the command.

Exit codes
----------
0
    Success.
1
    Failure during computation: an entry or plot of the scene failed (the
    other results are still written and the summary lists the failures), or
    a file could not be written or drawn (one line naming the file and why:
    "no space left on the device" of a full disk, ...).
2
    Bad scene or usage: malformed or missing scene (the message names the
    file, the key and what is allowed), unknown option, a file that is not
    an impactcont NetCDF file, an output path that cannot be written
    (checked before anything is computed).
130
    Interrupted (Ctrl-C).
"""

from __future__ import annotations

import argparse
import logging
import re
import sys
import warnings
from collections.abc import Callable, Sequence

__all__ = ["EXIT_FAILURE", "EXIT_INTERRUPTED", "EXIT_OK", "EXIT_USAGE", "main"]

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130

log = logging.getLogger("impactcont.cli")


class _UsageError(Exception):
    """Bad input from the command line: exit code 2."""


class _Formatter(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        record.levelname_lower = record.levelname.lower()
        return super().format(record)


def _out(text: str) -> None:
    sys.stdout.write(text if text.endswith("\n") else text + "\n")


#: A Sphinx role (``:func:`target```, ``:py:class:`title <target>```).
_ROLE = re.compile(r":(?:[\w-]+:)+`(?P<body>[^`]+)`")
#: Inline literal, hyperlink reference, interpreted text, strong, emphasis.
_INLINE = [re.compile(pattern) for pattern in (
    r"``(?P<body>.+?)``",
    r"`(?P<body>[^`<]+?)\s*(?:<[^`>]*>)?`__?",
    r"`(?P<body>[^`]+)`",
    r"(?<![\w*])\*\*(?P<body>\S(?:.*?\S)?)\*\*(?![\w*])",
    r"(?<![\w*])\*(?P<body>\S(?:[^*]*?\S)?)\*(?![\w*])",
)]


def _role_text(match: re.Match[str]) -> str:
    """What Sphinx shows for a role: its title, or its target (``~``: the last name only)."""
    body = match.group("body").strip()
    title = re.fullmatch(r"(?P<title>.+?)\s*<[^<>]+>", body)
    if title is not None:
        return title.group("title")
    body = body.lstrip("!")
    return body.lstrip("~").rpartition(".")[2] if body.startswith("~") else body


def plain_text(text: str) -> str:
    """``text`` (reStructuredText of a docstring) as a terminal shows it: the markup removed.

    Sphinx roles give their title or target (``:func:`~impactcont.curve``` -> ``curve``),
    inline literals, interpreted text, links, strong and emphasis their text.

    Parameters
    ----------
    text : str
        One line or paragraph of reStructuredText.

    Returns
    -------
    str
        The same text without markup.
    """
    text = _ROLE.sub(_role_text, text)
    for pattern in _INLINE:
        text = pattern.sub(lambda m: m.group("body"), text)
    return text


# ---------------------------------------------------------------------------------------------
# Commands
# ---------------------------------------------------------------------------------------------
def _cmd_run(args: argparse.Namespace) -> int:
    from impactcont.dataset.io import check_output_directory
    from impactcont.scene import SceneError, load_scene, run_scene

    try:
        scene = load_scene(args.scene, settings=args.set or (), output=args.output)
        # before computing anything (and in --check): can the outputs be written?
        check_output_directory(scene.output_dir, create=not args.check)
    except (SceneError, OSError) as exc:
        raise _UsageError(str(exc)) from None
    if args.check:
        counts = ", ".join(f"{len(e)} {k}" for k, e in scene.sections.items() if e) or "nothing"
        if not args.quiet:
            _out(f"{args.scene}: valid scene {scene.title!r}: {counts}, {len(scene.plots)} "
                 f"plot(s); output directory {scene.output_dir}")
        return EXIT_OK
    progress = args.progress
    if progress is None:
        progress = sys.stderr.isatty() and not args.quiet
    if progress and not args.quiet:
        try:
            import tqdm  # noqa: F401
        except ImportError:
            logging.getLogger("impactcont.progress").setLevel(logging.INFO)
    result = run_scene(scene, progress=progress, fail_fast=args.fail_fast)
    if not args.quiet:
        _out(f"wrote {len(result.files)} file(s) to {result.output_dir} in "
             f"{result.elapsed:.1f} s:")
        for path in result.files:
            _out(f"  {path.name}")
        _out(f"{len(result.special_points)} special point(s) found; see "
             f"{result.output_dir / 'summary.md'}" if scene.output.summary else
             f"{len(result.special_points)} special point(s) found")
    for failure in result.failures:
        log.error("%s %s: %s", failure.section, failure.name, failure.error)
    return EXIT_OK if result.ok else EXIT_FAILURE


def _read_error(exc: Exception) -> _UsageError:
    return _UsageError(str(exc))


class _Registry(Sequence[str]):
    """The names a registry of the plotting code holds, read when first needed.

    ``choices`` of an option: the registry (and matplotlib) is imported only when
    ``plot`` parses its options or prints its help, not for every command.
    """

    def __init__(self, load: Callable[[], Sequence[str]]) -> None:
        self._load = load
        self._names: tuple[str, ...] | None = None

    def _all(self) -> tuple[str, ...]:
        if self._names is None:
            self._names = tuple(self._load())
        return self._names

    def __getitem__(self, i):  # type: ignore[override]
        return self._all()[i]

    def __len__(self) -> int:
        return len(self._all())

    def __contains__(self, name: object) -> bool:
        return name in self._all()


def _plot_kind_names() -> list[str]:
    """The plot kinds of the scene sections (built-in and plugins)."""
    from impactcont.scene.plugins import plot_kinds

    return sorted(plot_kinds())


def _y_variables() -> tuple[str, ...]:
    """The variables a bifurcation diagram draws on its vertical axis."""
    from impactcont.plots.branches import Y_VARIABLES

    return Y_VARIABLES


def _plot_width(text: str) -> float:
    """``--width``: inches within :data:`impactcont.scene.figures.WIDTH_RANGE`."""
    from impactcont.errors import ParameterError
    from impactcont.scene.figures import check_width

    try:
        return check_width(float(text), "--width")
    except ValueError as exc:
        if isinstance(exc, ParameterError):
            raise argparse.ArgumentTypeError(str(exc)) from None
        raise argparse.ArgumentTypeError(
            f"--width must be a number of inches; got {text!r}") from None


def _cmd_plot(args: argparse.Namespace) -> int:
    from impactcont.scene.figures import plot_file

    try:
        written = plot_file(args.file, args.output, kind=args.kind, y=args.y, dpi=args.dpi,
                            width=args.width)
    except (FileNotFoundError, NotADirectoryError, PermissionError, ValueError) as exc:
        raise _read_error(exc) from None
    if not args.quiet:
        for path in written:
            _out(f"wrote {path}")
    return EXIT_OK


def _cmd_info(args: argparse.Namespace) -> int:
    from impactcont.scene.describe import describe_file

    try:
        text = describe_file(args.file)
    except (FileNotFoundError, ValueError) as exc:
        raise _read_error(exc) from None
    _out(text)
    return EXIT_OK


def _cmd_list_problems(args: argparse.Namespace) -> int:
    from impactcont.scene.plugins import list_problems

    problems = list_problems()
    rows = [(name, info.origin,
             f"[[{info.section.key}]]" if info.section is not None else "(no scene section)",
             info.target) for name, info in problems.items()]
    widths = [max(len(row[i]) for row in rows) for i in range(3)]
    for row, info in zip(rows, problems.values(), strict=True):
        _out("  ".join(f"{c:<{w}}" for c, w in zip(row, widths, strict=False)) + f"  {row[3]}")
        if info.summary and not args.quiet:
            _out(f"{'':<{widths[0]}}  {plain_text(info.summary)}")
    return EXIT_OK


# ---------------------------------------------------------------------------------------------
# Parser
# ---------------------------------------------------------------------------------------------
def _verbosity_options() -> argparse.ArgumentParser:
    common = argparse.ArgumentParser(add_help=False)
    group = common.add_mutually_exclusive_group()
    group.add_argument("-v", "--verbose", action="count", default=argparse.SUPPRESS,
                       help="more logging: -v info, -vv debug")
    group.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS,
                       help="errors only, and no summary on stdout")
    return common


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``impactcont``."""
    from impactcont import __version__

    common = _verbosity_options()
    parser = argparse.ArgumentParser(
        prog="impactcont", parents=[common],
        description="Bifurcation analysis of vibro-impact oscillators: run a scene (a TOML "
                    "study description), describe and draw the NetCDF files it writes.",
        epilog="exit codes: 0 success, 1 failure during computation, 2 bad scene or usage "
               "(including an output path that cannot be written), 130 interrupted. "
               "Documentation: docs/ (mkdocs).")
    parser.add_argument("--version", action="version", version=f"impactcont {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    run = sub.add_parser("run", parents=[common], help="compute a scene",
                         description="Compute a scene and write NetCDF, PNG and summary.md.")
    run.add_argument("scene", metavar="SCENE.toml", help="the scene file")
    run.add_argument("--output", "-o", metavar="DIR",
                     help="output directory (default: output.directory of the scene, "
                          "relative to the scene file)")
    run.add_argument("--set", action="append", metavar="KEY=VALUE",
                     help="override a scene key, e.g. --set oscillator.b=0.5 or "
                          "--set 'branches[0].bounds=[0.5, 3]' (repeatable; values are TOML, "
                          "else strings)")
    run.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                     help="progress bar on stderr (default: when stderr is a terminal)")
    run.add_argument("--fail-fast", action="store_true",
                     help="stop at the first failing entry (default: go on with the others)")
    run.add_argument("--check", action="store_true",
                     help="only validate the scene; compute nothing")
    run.set_defaults(func=_cmd_run)

    plot = sub.add_parser("plot", parents=[common], help="draw a NetCDF file",
                          description="Draw a NetCDF file written by 'impactcont run'.")
    plot.add_argument("file", metavar="FILE.nc")
    plot.add_argument("-o", "--output", metavar="PNG",
                      help="PNG to write (default: FILE.png beside the file)")
    plot.add_argument("--kind", choices=_Registry(_plot_kind_names), metavar="KIND",
                      help="plot kind, one of %(choices)s (default: the usual one for the "
                           "file)")
    plot.add_argument("--y", choices=_Registry(_y_variables), metavar="VARIABLE",
                      help="bifurcation diagram: variable on the vertical axis, one of "
                           "%(choices)s (default impact_velocity)")
    plot.add_argument("--dpi", type=int, default=150,
                      help="resolution in dots per inch, 10 to 1200 (default 150)")
    plot.add_argument("--width", type=_plot_width, default=7.0, metavar="INCHES",
                      help="figure width in inches, 2 to 7.2 (3.5: a journal's column; "
                           "default 7)")
    plot.set_defaults(func=_cmd_plot)

    info = sub.add_parser("info", parents=[common], help="describe a NetCDF file",
                          description="Describe what a NetCDF file of impactcont holds.")
    info.add_argument("file", metavar="FILE.nc")
    info.set_defaults(func=_cmd_info)

    problems = sub.add_parser("list-problems", parents=[common],
                              help="list built-in and plugin problems and their scene sections",
                              description="List the problems a scene can run: built-in ones "
                                          "and those of the entry-point group "
                                          "impactcont.problems, with the scene section "
                                          "([[key]]) each brings.")
    problems.set_defaults(func=_cmd_list_problems)
    return parser


class _Logging:
    """Logging of the ``impactcont`` loggers to stderr for one call of :func:`main`."""

    def __init__(self, verbose: int, quiet: bool) -> None:
        level = logging.ERROR if quiet else {0: logging.WARNING, 1: logging.INFO}.get(
            verbose, logging.DEBUG)
        fmt = ("%(levelname_lower)s: %(name)s: %(message)s" if level == logging.DEBUG
               else "%(levelname_lower)s: %(message)s")
        self.handler = logging.StreamHandler(sys.stderr)
        self.handler.setFormatter(_Formatter(fmt))
        self.loggers = [logging.getLogger("impactcont"), logging.getLogger("py.warnings")]
        self.saved = [(lg, lg.level) for lg in
                      [*self.loggers, logging.getLogger("impactcont.progress")]]
        for lg in self.loggers:
            lg.addHandler(self.handler)
            lg.setLevel(level)

    def close(self) -> None:
        for lg in self.loggers:
            lg.removeHandler(self.handler)
        for lg, level in self.saved:
            lg.setLevel(level)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``impactcont`` command line; return the exit code.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name (default ``sys.argv[1:]``).

    Returns
    -------
    int
        0 success, 1 failure during computation, 2 bad scene or usage,
        130 interrupted.
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, or a usage error (argparse printed it)
        return int(exc.code) if isinstance(exc.code, int) else EXIT_USAGE
    args.verbose = getattr(args, "verbose", 0)
    args.quiet = getattr(args, "quiet", False)
    if args.command is None:
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    logs = _Logging(args.verbose, args.quiet)
    func: Callable[[argparse.Namespace], int] = args.func
    try:
        with warnings.catch_warnings():
            logging.captureWarnings(True)
            return func(args)
    except _UsageError as exc:
        log.error("%s", exc)
        return EXIT_USAGE
    except KeyboardInterrupt:
        log.error("interrupted")
        return EXIT_INTERRUPTED
    except OSError as exc:  # a file not written: impactcont's message names it and says why
        log.error("%s", exc, exc_info=args.verbose >= 2)
        return EXIT_FAILURE
    except Exception as exc:
        log.error("%s: %s", type(exc).__name__, exc, exc_info=args.verbose >= 2)
        return EXIT_FAILURE
    finally:
        logging.captureWarnings(False)
        logs.close()

