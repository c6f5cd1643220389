"""The sweep target of issue 30: no simulation ends at CHATTER or STICKING unless asked, and
every trajectory keeps every stop coordinate on its side of every stop.

Two sweeps, as the issue measured them:

(a) a seeded random sweep of machines of the new classes (impact dampers, balls under
    gravity on tables and on floors, free chains, clearances in chains, stiff chains; n = 2-4,
    R = 0.3-1, omega 0.2-5 times the lowest natural frequency), each simulated from a generic
    state (random positions inside the stops, random velocities);
(b) brute-force sweeps from rest over omega in [0.2, 4] (39 values) for the paper's system at
    b = 0.1, the impact damper of docs/machines.md (ball mass 0.2, clearance +-0.3, R = 0.6)
    and a one-mass oscillator preloaded into its stop (F_static = 1 into b = 0).

Each run is tabulated by how it ended (its status), its impacts, sticking phases and chatter
accumulation points, and the largest excursion of every stop coordinate past every stop along
the whole trajectory: the trajectory sampled densely between the events (``samples_per_period``
samples a forcing period, both sides of each impact) and the state at every impact, at the
start of every sticking phase and at every accumulation point. A run is capped in processor
time (``--cap`` seconds of this process's CPU time, so that the cap means the same on a
loaded machine; reported as its own status ``CPU_CAP``, with the forcing periods it reached)
and in impacts (``max_impacts``, status ``MAX_IMPACTS``). Each run is written as a line of
JSON to ``--log`` as it ends; ``--table-from`` tabulates such a file.

Run (from a clean clone, as the README's table was made)::

    python studies/chatter_sticking/sweep.py [--systems 480] [--periods 5]
        [--bf-periods 20] [--cap 30] [--log runs.jsonl]
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import json
import logging
import math
import signal
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import scipy.linalg

import impactcont as ic
from impactcont.model.stops import Stops

log = logging.getLogger("chatter_sticking.sweep")

CLASSES = ("impact damper", "ball on a table", "balls on a floor", "free chain",
           "clearance in a chain", "stiff chain")
# an excursion past a stop larger than this many ulps of the state's size is a violation
VIOLATION_ULPS = 1024
_EPS = float(np.finfo(float).eps)


class CapError(Exception):
    """A run reached its processor-time cap."""


@dataclasses.dataclass(frozen=True)
class Run:
    """One simulation of a sweep: the machine's class, how the run ended and what it met."""

    kind: str
    label: str
    status: str
    impacts: int
    sticking: int
    chatter: int
    violation: float  # the largest excursion past a stop (<= 0: none), over every stop
    allowed: float  # rounding: VIOLATION_ULPS ulps of the stop's position and the state's size
    periods: float  # forcing periods simulated (less than asked at a cap)
    seconds: float  # wall time
    cpu: float = math.nan  # processor time of this process (nan: a log written before it)

    @property
    def violates(self) -> bool:
        """The run put a stop coordinate past its stop by more than rounding."""
        return self.violation > self.allowed


def lowest_frequency(M: np.ndarray, K: np.ndarray) -> float:
    """The lowest nonzero natural frequency of (M, K) (free modes left out)."""
    lam = scipy.linalg.eigh(K, M, eigvals_only=True)
    lam = lam[lam > 1e-9 * max(1.0, float(np.abs(lam).max()))]
    return float(math.sqrt(lam.min()))


def chain_K(springs: np.ndarray, ground: float) -> np.ndarray:
    """Masses 1..n in a line: mass i joined to i+1 by springs[i], mass n to the ground."""
    n = springs.size + 1
    K = np.zeros((n, n))
    for i, k in enumerate(springs):
        K[i, i] += k
        K[i + 1, i + 1] += k
        K[i, i + 1] -= k
        K[i + 1, i] -= k
    K[n - 1, n - 1] += ground
    return K


def random_machine(kind: str, rng: np.random.Generator
                   ) -> tuple[ic.ImpactOscillator, np.ndarray, float]:
    """One machine of class `kind` (:data:`CLASSES`) and a generic start (state, phase).

    Every class has n = 2-4 masses, R in [0.3, 1], eta in [0, 0.1] (C = 2 eta K, so free
    modes are undamped) and omega in 0.2-5 times its lowest natural frequency.
    """
    n = int(rng.integers(2, 5))
    R = float(rng.uniform(0.3, 1.0))
    eta = float(rng.uniform(0.0, 0.1))
    m = rng.uniform(0.5, 1.5, n)
    F = np.zeros(n)
    F_static = np.zeros(n)
    v = rng.uniform(-1.0, 1.0, n)
    x = np.zeros(n)
    if kind == "impact damper":  # a chain of n-1 masses, a free ball n in a clearance +-gap
        gap = float(rng.uniform(0.1, 0.5))
        m[-1] = rng.uniform(0.05, 0.5)
        K = _with_free_ball(chain_K(rng.uniform(0.5, 2.0, n - 2), 1.0))
        F[0] = 1.0
        stops = Stops(mass=n, relative_to=1, mirror=True)
        b = gap
        x[:-1] = rng.uniform(-0.5, 0.5, n - 1)
        x[-1] = x[0] + rng.uniform(-gap, gap)
    elif kind == "ball on a table":  # a table of n-1 masses, ball n under gravity on mass 1
        m[-1] = rng.uniform(0.05, 0.5)
        K = _with_free_ball(chain_K(rng.uniform(0.5, 2.0, n - 2), 1.0))
        g = float(rng.uniform(0.2, 1.0))
        F[0] = rng.uniform(0.5, 2.0)
        F_static[-1] = -g * m[-1]
        stops = Stops(mass=n, relative_to=1, b_low=0.0, R_low=R)
        b = 50.0
        x[:-1] = rng.uniform(-0.5, 0.5, n - 1)
        x[-1] = x[0] + rng.uniform(0.0, 0.5)
    elif kind == "balls on a floor":  # a free chain under gravity, mass 1 on a floor x1 = 0
        K = chain_K(rng.uniform(0.5, 2.0, n - 1), 0.0)
        g = float(rng.uniform(0.2, 1.0))
        F[-1] = rng.uniform(0.5, 2.0)
        F_static[:] = -g * m
        stops = Stops(b_low=0.0, R_low=R)
        b = 50.0
        x[:] = rng.uniform(0.0, 0.5) + rng.uniform(-0.1, 0.1, n)
        x[0] = abs(x[0])
    elif kind == "free chain":  # no spring to the ground, a two-sided stop on mass 1
        K = chain_K(rng.uniform(0.5, 2.0, n - 1), 0.0)
        F[-1] = 1.0
        b = float(rng.uniform(0.1, 0.5))
        stops = Stops(mirror=True)
        x[:] = rng.uniform(-b, b, n)
    elif kind == "clearance in a chain":  # a grounded chain, masses j, j+1 meet in a clearance
        K = chain_K(rng.uniform(0.5, 2.0, n - 1), float(rng.uniform(0.5, 2.0)))
        F[0] = 1.0
        j = int(rng.integers(1, n))
        gap = float(rng.uniform(0.05, 0.5))
        low = float(rng.uniform(0.05, 0.5))
        stops = Stops(mass=j + 1, relative_to=j, b_low=low, R_low=float(rng.uniform(0.3, 1.0)))
        b = gap
        x[:] = rng.uniform(-0.3, 0.3, n)
        x[j] = x[j - 1] + rng.uniform(-low, gap)
    elif kind == "stiff chain":  # springs over three decades, a stop above mass 1
        K = chain_K(10.0 ** rng.uniform(-1.0, 2.0, n - 1), float(10.0 ** rng.uniform(-1, 2)))
        F[-1] = 1.0
        b = float(rng.uniform(0.0, 0.3))
        stops = None
        x[:] = rng.uniform(-0.3, 0.3, n)
        x[0] = min(x[0], b)
    else:
        raise ValueError(f"kind must be one of {CLASSES}; got {kind!r}")
    M = np.diag(m)
    omega = float(rng.uniform(0.2, 5.0)) * lowest_frequency(M, K)
    osc = ic.ImpactOscillator(M=M, K=K, F=F, R=R, b=b, omega=omega, eta=eta, stops=stops,
                              F_static=F_static)
    return osc, np.concatenate([x, v]), float(rng.uniform(-math.pi, math.pi))


def _with_free_ball(K: np.ndarray) -> np.ndarray:
    """K of a chain with one more mass, on no spring (a free ball)."""
    n = K.shape[0] + 1
    out = np.zeros((n, n))
    out[:-1, :-1] = K
    return out


def excursion(osc: ic.ImpactOscillator, res: ic.SimulationResult) -> tuple[float, float]:
    """The largest excursion of any stop coordinate past its stop, and rounding's allowance.

    Over the trajectory's samples (both sides of every impact), the states right after the
    impacts and at the starts of the sticking phases. Returns ``(excursion, allowed)``: the
    excursion is ``max sign (s - position)`` over every stop and every state (negative: the
    motion never reached a stop), and ``allowed`` is ``VIOLATION_ULPS`` ulps of the stop's
    position plus the largest entry of the state along the run, positions and velocities:
    the flow sums every coordinate from modal terms of the whole state's size, so a
    coordinate that stays near 0 beside masses far from 0 is known only to ulps of theirs.
    """
    n = osc.n
    states = [res.X, res.impact_states]
    states += [p.start_state[None, :] for p in res.sticking]
    full = np.vstack(states)
    X = full[:, :n]
    size = float(np.abs(full).max(initial=0.0))
    worst, allowed = -math.inf, 0.0
    for name in osc.stops.names:
        view = osc.stops.stop(name, osc.M, osc.b, osc.R)
        s = X @ view.normal
        past = view.sign * (s - view.position)
        k = int(np.argmax(past))
        if past[k] > worst:
            worst = float(past[k])
            allowed = VIOLATION_ULPS * _EPS * (abs(view.position) + size)
    return worst, allowed


def _alarm(signum: int, frame: object) -> None:
    raise CapError


def run(kind: str, label: str, osc: ic.ImpactOscillator, X0: np.ndarray, delta: float,
        periods: float, cap: float, *, samples_per_period: int = 400,
        max_impacts: int = 200_000) -> Run:
    """Simulate one machine (through chatter and sticking: ``stop_at`` empty) under a cap of
    `cap` seconds of processor time, in slices of at most 5 forcing periods (so a capped run
    still reports the periods it reached)."""
    start, cpu_start = time.perf_counter(), time.process_time()
    previous = signal.signal(signal.SIGVTALRM, _alarm)
    signal.setitimer(signal.ITIMER_VIRTUAL, cap)
    X, phase, done = np.asarray(X0, float), float(delta), 0.0
    impacts = sticking = chatter = 0
    worst, allowed = -math.inf, 0.0
    status = "COMPLETED"
    try:
        while done < periods * (1 - 1e-12):
            span = min(5.0, periods - done)
            res = ic.simulate(osc, X, phase, span, trajectory=True,
                              samples_per_period=samples_per_period,
                              max_impacts=max(1, max_impacts - impacts))
            impacts += res.impact_times.size
            sticking += len(res.sticking)
            chatter += len(res.chatter)
            e, a = excursion(osc, res)
            if e > worst:
                worst, allowed = e, a
            done += res.final_time * osc.omega / (2 * math.pi)
            X, phase = res.final_state, res.final_phase
            if not res.success:
                status = res.status.name
                break
    except CapError:
        status = "CPU_CAP"
    except Exception as exc:  # a finding: reported with its type, the sweep goes on
        log.error("%s %s: %s: %s", kind, label, type(exc).__name__, exc)
        status = f"ERROR ({type(exc).__name__})"
    finally:
        signal.setitimer(signal.ITIMER_VIRTUAL, 0.0)
        signal.signal(signal.SIGVTALRM, previous)
    return Run(kind, label, status, impacts, sticking, chatter, worst, allowed, done,
               time.perf_counter() - start, time.process_time() - cpu_start)


def random_sweep(systems: int, periods: float, cap: float, seed: int = 30,
                 part: tuple[int, int] | None = None) -> Iterator[Run]:
    """Sweep (a): `systems` random machines, the classes in turn, `periods` periods each;
    only the machines ``part[0] <= i < part[1]`` if `part` is given (the same machines as
    in the whole sweep: every machine is drawn, in order, from the one seeded generator)."""
    rng = np.random.default_rng(seed)
    first, last = part if part is not None else (0, systems)
    for i in range(systems):
        kind = CLASSES[i % len(CLASSES)]
        osc, X0, delta = random_machine(kind, rng)
        if first <= i < last:
            yield run(kind, f"#{i}", osc, X0, delta, periods, cap)


def paper_b01(omega: float) -> ic.ImpactOscillator:
    """Cao & Shu section 4 at b = 0.1."""
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                               R=0.6, b=0.1, omega=omega, eta=0.1)


def machines_damper(omega: float) -> ic.ImpactOscillator:
    """The impact damper of docs/machines.md: ball mass 0.2 in a clearance +-0.3, R = 0.6."""
    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1, 0], R=0.6,
                               b=0.3, omega=omega, eta=0.02,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


def preloaded(omega: float) -> ic.ImpactOscillator:
    """One mass pushed into its stop b = 0 by F_static = 1, forced 3 cos(omega t)."""
    return ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.5, b=0.0,
                               omega=omega, eta=0.05)


BRUTE_FORCE: dict[str, Callable[[float], ic.ImpactOscillator]] = {
    "paper, b = 0.1": paper_b01, "impact damper (machines.md)": machines_damper,
    "preloaded oscillator": preloaded}


def brute_force(periods: float, cap: float, omegas: np.ndarray,
                part: tuple[int, int] | None = None) -> Iterator[Run]:
    """Sweep (b): each system of :data:`BRUTE_FORCE` from rest at every omega; only the
    runs ``part[0] <= i < part[1]`` of that order if `part` is given."""
    first, last = part if part is not None else (0, len(BRUTE_FORCE) * omegas.size)
    i = 0
    for name, make in BRUTE_FORCE.items():
        for omega in omegas:
            if first <= i < last:
                osc = make(float(omega))
                yield run(name, f"omega={omega:.1f}", osc, np.zeros(2 * osc.n), 0.0, periods,
                          cap)
            i += 1


def table(runs: list[Run]) -> list[str]:
    """The sweep's table by class: ends, events, the largest excursion past a stop."""
    rows = ["| class | runs | ended | impacts | sticking phases | chatter points | "
            "largest excursion past a stop | past by more than rounding | wall (s) | CPU (s) |",
            "|---|---|---|---|---|---|---|---|---|---|"]
    kinds = list(dict.fromkeys(r.kind for r in runs))
    for kind in [*kinds, "all"]:
        sel = [r for r in runs if kind in ("all", r.kind)]
        ends = collections.Counter(r.status for r in sel)
        ended = ", ".join(f"{k} {v}" for k, v in sorted(ends.items(), key=lambda kv: -kv[1]))
        worst = max(r.violation for r in sel)
        rows.append(
            f"| {kind} | {len(sel)} | {ended} | {sum(r.impacts for r in sel)} | "
            f"{sum(r.sticking for r in sel)} | {sum(r.chatter for r in sel)} | "
            f"{_excursion(worst)} | {sum(r.violates for r in sel)} | "
            f"{sum(r.seconds for r in sel):.0f} | {sum(r.cpu for r in sel):.0f} |")
    return rows


def throughput(runs: list[Run]) -> list[str]:
    """Processor time by class: per 200 forcing periods (median and largest, with the slowest
    run's impacts a period and accumulation points) and per thousand impacts."""
    rows = ["| class | CPU s / 200 periods, median | largest (run) | its impacts a period | "
            "its chatter points | CPU s / 1000 impacts, median |", "|---|---|---|---|---|---|"]
    for kind in dict.fromkeys(r.kind for r in runs):
        sel = [r for r in runs if r.kind == kind and math.isfinite(r.cpu) and r.periods > 0]
        if not sel:
            continue
        per = [200.0 * r.cpu / r.periods for r in sel]
        k = int(np.argmax(per))
        slow = sel[k]
        per_impact = [1000.0 * r.cpu / r.impacts for r in sel if r.impacts]
        rows.append(
            f"| {kind} | {float(np.median(per)):.2g} | {per[k]:.3g} ({slow.label}, "
            f"{slow.status}) | {slow.impacts / slow.periods:.3g} | {slow.chatter} | "
            f"{float(np.median(per_impact)) if per_impact else math.nan:.2g} |")
    return rows


def _excursion(e: float) -> str:
    return "never reached" if e == -math.inf else (f"{e:.1e}" if e > 0 else f"{e:.1e} (short)")


def findings(runs: list[Run]) -> list[str]:
    """Every run that did not complete or crossed a stop."""
    return [f"- {r.kind} {r.label}: {r.status} after {r.periods:.2f} periods, {r.impacts} "
            f"impacts, excursion {r.violation:.2e} (allowed {r.allowed:.1e}), {r.seconds:.1f} s"
            for r in runs if r.status != "COMPLETED" or r.violates]


def main(argv: list[str] | None = None) -> None:
    """Run both sweeps and print their tables (markdown) and findings."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--systems", type=int, default=480)
    parser.add_argument("--periods", type=float, default=5.0,
                        help="forcing periods of each random machine")
    parser.add_argument("--bf-periods", type=float, default=20.0,
                        help="forcing periods of each brute-force run")
    parser.add_argument("--cap", type=float, default=30.0,
                        help="processor seconds per run")
    parser.add_argument("--seed", type=int, default=30)
    parser.add_argument("--part", type=int, nargs=2, default=None, metavar=("FIRST", "STOP"),
                        help="run only the random machines FIRST <= i < STOP (a sweep split "
                             "over processes; --table-from joins their logs)")
    parser.add_argument("--bf-part", type=int, nargs=2, default=None, metavar=("FIRST", "STOP"),
                        help="run only the brute-force runs FIRST <= i < STOP (of the 3 x 39)")
    parser.add_argument("--skip-random", action="store_true")
    parser.add_argument("--skip-brute-force", action="store_true")
    parser.add_argument("--log", type=Path, default=None,
                        help="write each run as a line of JSON to this file as it ends")
    parser.add_argument("--table-from", type=Path, default=None,
                        help="only tabulate the runs of such a file")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.ERROR, format="%(message)s")
    if args.table_from is not None:
        runs = [Run(**json.loads(line)) for line in args.table_from.read_text().splitlines()]
        for sweep in ("random", "brute force"):
            part = [r for r in runs if (r.kind in CLASSES) == (sweep == "random")]
            if part:
                print(f"\n## {sweep}: {len(part)} runs\n")
                print("\n".join([*table(part), "", *throughput(part), "",
                                  *findings(part)]))
        return
    start = time.perf_counter()
    log_file = args.log.open("a") if args.log else None

    def logged(runs: Iterator[Run]) -> list[Run]:
        out = []
        for r in runs:
            out.append(r)
            if log_file:
                log_file.write(json.dumps(dataclasses.asdict(r)) + "\n")
                log_file.flush()
        return out

    if not args.skip_random:
        runs = logged(random_sweep(args.systems, args.periods, args.cap, args.seed,
                                   args.part))
        print(f"\n## (a) {args.systems} random machines, {args.periods:g} forcing periods "
              f"from a generic state (seed {args.seed}, cap {args.cap:g} CPU s a run)\n")
        print("\n".join(table(runs)))
        print("\n".join(["", *findings(runs)]))
    if not args.skip_brute_force:
        omegas = np.round(np.linspace(0.2, 4.0, 39), 10)
        runs = logged(brute_force(args.bf_periods, args.cap, omegas, args.bf_part))
        print(f"\n## (b) brute force from rest, 39 omega in [0.2, 4], {args.bf_periods:g} "
              f"forcing periods (cap {args.cap:g} CPU s a run)\n")
        print("\n".join(table(runs)))
        print("\n".join(["", *findings(runs)]))
    print(f"\n(total {time.perf_counter() - start:.0f} s wall, "
          f"{time.process_time():.0f} s CPU)")


if __name__ == "__main__":
    main()
