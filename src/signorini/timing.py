"""A timing protocol whose ratios survive a loaded machine.

What inflates a solver's wall time on a shared machine, and what this protocol does about it:

1. **Time sharing** (more runnable threads than cores): the process waits for a core, its wall
   time grows by 1/(its CPU share).  The *CPU time* of a single-threaded call does not grow:
   every call is timed with ``time.process_time`` (a PETSc peer by its driver, around its
   ``solve`` only) next to ``time.perf_counter``; their quotient is the CPU share the call got.
2. **Contention for caches and memory bandwidth, clock frequency**: these slow the CPU time
   too.  A *reference kernel* (``ReferenceKernel``: a numerical sparse Cholesky factorisation
   of the measured system's own matrix and CSR products with it, the two kinds of work the
   solvers do) is timed immediately before and after every call, and each time is also given
   in *reference units* (CPU time of the call / mean CPU time of the two kernels around it).
   A uniform slowdown cancels; one that changes within a call is bracketed.
3. **Load bursts**: every sample records the 1-minute load average before and after the call
   and the call's CPU share; a sample taken under a load above ``max_load`` (default: the
   usable cores) or with a CPU share below ``min_cpu_share`` is *rejected* and redone later
   (after a bounded wait for the load to fall; in ``round_robin`` after the other tasks of the
   round), at most ``retries`` times per measurement; a sample accepted after the last retry
   says so (``loaded``).
4. **Short calls**: a call whose first run took less than ``min_sample_s`` (wall time of the
   whole call: a peer's includes its interpreter's start, which its own timer leaves out) is run
   ``calls`` times in a row per later sample (as ``timeit`` does), enough to last
   ``min_sample_s``; the sample's times are per call, so a call of milliseconds is not timed
   near the clocks' resolution.  It does not remove the variation of the CPU time itself from
   one second to the next: on a quiet machine the batches of 0.1-0.5 s calls (N = 201) still
   spread by 10-17 % over 7 samples (``docs/evidence/timing_robustness*.json``).
5. **Noise**: a measurement is repeated until ``min_repeats`` samples agree within ``spread``
   (relative range of their CPU times, the quantity the study ranks by), at most
   ``max_repeats`` times and no new sample after ``budget_s`` seconds (a call longer than that
   is timed once: it averages the load over its own duration).  The reported value is the median.

Round-robin scheduling (``round_robin``) interleaves the samples of several tasks, so that
when the load changes slowly all tasks see it alike; it cannot help against load that changes
within seconds, which is what points 1 and 2 are for.  Per-job timing (the work-precision
study's one job per mesh and configuration) therefore stays comparable across jobs through
the CPU time and the reference units, not through scheduling.

The clocks, the load and the sleep are a ``Machine`` (fakes in the tests); ``machine_record``
names what a measurement ran on (cores, CPU model, virtualisation, thread settings, software).
"""

from __future__ import annotations

import contextlib
import math
import os
import platform
import statistics
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np


def usable_cores() -> int:
    """The cores this process may run on (its affinity mask; ``os.cpu_count()`` without one)."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def _load1() -> float:
    return os.getloadavg()[0]


@dataclass
class Machine:
    """Where the protocol reads time and load: wall clock, this process's CPU clock, the
    1-minute load average, the number of cores, and how it waits."""

    wall: Callable[[], float] = time.perf_counter
    cpu: Callable[[], float] = time.process_time
    load: Callable[[], float] = _load1
    sleep: Callable[[float], None] = time.sleep
    cores: int = field(default_factory=usable_cores)


@dataclass(frozen=True)
class Protocol:
    """The protocol's parameters (a study's ``timing`` block; see the module docstring)."""

    min_repeats: int = 3
    max_repeats: int = 7
    spread: float = 0.05
    budget_s: float = 20.0
    max_load: float | None = None  # None: the usable cores
    min_cpu_share: float = 0.9
    retries: int = 3
    wait_s: float = 30.0  # longest wait for the load to fall before a redo
    poll_s: float = 2.0
    max_wait_total_s: float = 600.0  # all waits of one Timer together
    min_sample_s: float = 1.0  # shorter calls are batched to last this long per sample

    def calls_for(self, span_s: float) -> int:
        """Calls per sample for a call that lasted ``span_s`` seconds (at most ``MAX_CALLS``)."""
        if span_s >= self.min_sample_s:
            return 1
        return min(MAX_CALLS, math.ceil(self.min_sample_s / max(span_s, 1e-6) - 1e-9))

    @classmethod
    def from_mapping(cls, spec: Mapping | None) -> Protocol:
        """A protocol from a mapping of some of its fields (unknown keys: ``ValueError``)."""
        spec = dict(spec or {})
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(spec) - known)
        if unknown:
            raise ValueError(f"timing: unknown keys {unknown}; known: {sorted(known)}")
        return cls(**spec)

    def as_dict(self) -> dict:
        return asdict(self)


MAX_CALLS = 100  # calls per sample, at most
KERNEL_MIN_UNKNOWNS = 20_000  # a small system's kernel is repeated up to this many unknowns


class ReferenceKernel:
    """A fixed amount of sparse work on the matrix ``A`` of the measured problem: one numerical
    Cholesky factorisation (the project's ``Factorizer``: CHOLMOD, else SuperLU; symbolic
    analysis done once here) and ``matvecs`` CSR products, repeated ``ceil(20 000 / n)`` times
    for ``n`` unknowns (so that a small mesh's kernel lasts tens of milliseconds, well above the
    clocks' resolution).  ``run()`` returns (wall, CPU) seconds."""

    def __init__(self, A, matvecs: int = 20, machine: Machine | None = None):
        import scipy.sparse as sp

        from signorini.solvers.linalg import Factorizer

        self.A = sp.csr_matrix(A)
        self.matvecs = int(matvecs)
        self.repeats = max(1, math.ceil(KERNEL_MIN_UNKNOWNS / self.A.shape[0]))
        self.machine = machine or Machine()
        self.factorizer = Factorizer(self.A)
        self.x = np.linspace(0.0, 1.0, self.A.shape[0])
        self.run()  # first touch of the memory and the libraries, outside any measurement

    @property
    def description(self) -> str:
        n = self.A.shape[0]
        return f"{self.repeats} × ({self.factorizer.backend} factorisation + {self.matvecs} CSR products), n = {n}"

    def run(self) -> tuple[float, float]:
        m = self.machine
        w0, c0 = m.wall(), m.cpu()
        for _ in range(self.repeats):
            self.factorizer(self.A.data)
            y = self.x
            for _ in range(self.matvecs):
                y = self.A @ y
                y *= 1.0 / max(float(np.abs(y).max()), 1e-300)
        return m.wall() - w0, m.cpu() - c0


@dataclass
class Sample:
    """One timed batch of ``calls`` calls: wall and CPU seconds per call, the reference kernel's CPU
    and wall seconds around it (mean of before and after), the load before/after, and whether it
    was rejected."""

    wall_s: float
    cpu_s: float
    ref_cpu_s: float
    ref_wall_s: float
    load_before: float
    load_after: float
    rejected: str = ""
    calls: int = 1
    span_s: float = math.nan  # wall seconds of one whole call, the callee's own overhead included

    @property
    def load(self) -> float:
        return max(self.load_before, self.load_after)

    @property
    def cpu_share(self) -> float:
        return self.cpu_s / self.wall_s if self.wall_s > 0 else math.nan

    @property
    def ref_units(self) -> float:
        """CPU time in reference units."""
        return self.cpu_s / self.ref_cpu_s if self.ref_cpu_s > 0 else math.nan

    @property
    def wall_ref_units(self) -> float:
        return self.wall_s / self.ref_wall_s if self.ref_wall_s > 0 else math.nan

    def as_dict(self) -> dict:
        return {**asdict(self), "ref_units": self.ref_units, "cpu_share": self.cpu_share}


# what a timed callable returns: (result, None) — timed here — or (result, (wall_s, cpu_s))
# measured by the callee itself (a peer's driver around its solve)
Timed = tuple[Any, "tuple[float, float] | None"]


class CallFailed(Exception):
    """Raised by ``Timer.measure`` when the timed call raised; carries the samples before it."""

    def __init__(self, error: BaseException, elapsed: float, samples: list[Sample]):
        super().__init__(str(error))
        self.error, self.elapsed, self.samples = error, elapsed, samples


@dataclass
class Measurement:
    """The accepted samples of one measurement, the rejected ones, why it stopped, the last result."""

    samples: list[Sample]
    rejected: list[Sample]
    stop: str
    result: Any = None
    waited_s: float = 0.0

    def summary(self, protocol: Protocol, cores: int) -> dict:
        """Record fields: medians of the accepted samples, spread, counts, loads."""
        s = self.samples
        if not s:
            return {"time_runs": 0, "rejected": len(self.rejected), "time_stop": self.stop}
        units = [x.ref_units for x in s]
        cpu = [x.cpu_s for x in s]
        limit = protocol.max_load if protocol.max_load is not None else float(cores)
        return {
            "time_s": statistics.median(cpu),
            "wall_s": statistics.median(x.wall_s for x in s),
            "time_ref": statistics.median(units),
            "wall_ref": statistics.median(x.wall_ref_units for x in s),
            "ref_s": statistics.median(x.ref_cpu_s for x in s),
            "cpu_share": statistics.median(x.cpu_share for x in s),
            "spread": spread(cpu),
            "time_runs": len(s),
            "rejected": len(self.rejected),
            "loaded": any(x.load > limit or x.cpu_share < protocol.min_cpu_share for x in s),
            "load1": statistics.median(x.load for x in s),
            "load1_max": max(x.load for x in s),
            "time_stop": self.stop,
            "calls": max(x.calls for x in s),
            "waited_s": self.waited_s,
            "times": " ".join(f"{x.cpu_s:.6g}" for x in s),
        }


def spread(values: Sequence[float]) -> float:
    """Relative range (max − min) / median; 0 for fewer than two values."""
    v = [float(x) for x in values if math.isfinite(x)]
    if len(v) < 2:
        return 0.0
    mid = statistics.median(v)
    return (max(v) - min(v)) / mid if mid > 0 else math.inf


class Timer:
    """Timing under a ``Protocol`` on a ``Machine``; keeps the total time waited for the load."""

    def __init__(self, protocol: Protocol | None = None, machine: Machine | None = None):
        self.protocol = protocol or Protocol()
        self.machine = machine or Machine()
        self.waited_s = 0.0

    @property
    def max_load(self) -> float:
        p = self.protocol
        return float(p.max_load) if p.max_load is not None else float(self.machine.cores)

    def wait_for_quiet(self) -> float:
        """Wait (at most ``wait_s``, within the Timer's ``max_wait_total_s``) until the load is at
        most ``max_load``; returns the seconds waited."""
        p, m = self.protocol, self.machine
        waited = 0.0
        while m.load() > self.max_load and waited < p.wait_s and self.waited_s + waited < p.max_wait_total_s:
            step = min(p.poll_s, p.wait_s - waited)
            m.sleep(step)
            waited += step
        self.waited_s += waited
        return waited

    def rejection(self, s: Sample) -> str:
        """Why a sample is rejected ('' when it is not)."""
        if s.load > self.max_load:
            return f"load {s.load:.2f} > {self.max_load:g}"
        if s.cpu_share < self.protocol.min_cpu_share:
            return f"CPU share {s.cpu_share:.2f} < {self.protocol.min_cpu_share:g}"
        return ""

    def sample(
        self, call: Callable[[], Timed], kernel: ReferenceKernel, ref_before: tuple[float, float], calls: int = 1
    ):
        """``calls`` calls in a row bracketed by the kernel: (the last result, Sample, the kernel's
        time after it)."""
        m = self.machine
        load_before = m.load()
        wall_s = cpu_s = 0.0
        started = m.wall()
        for _ in range(calls):
            w0, c0 = m.wall(), m.cpu()
            result, own = call()
            w1, c1 = m.wall(), m.cpu()
            own_wall, own_cpu = own if own is not None else (w1 - w0, c1 - c0)
            wall_s, cpu_s = wall_s + own_wall, cpu_s + own_cpu
        span_s = (m.wall() - started) / calls
        load_after = m.load()
        ref_after = kernel.run()
        ref_wall, ref_cpu = (ref_before[0] + ref_after[0]) / 2, (ref_before[1] + ref_after[1]) / 2
        per_call = (float(wall_s) / calls, float(cpu_s) / calls)
        s = Sample(*per_call, ref_cpu, ref_wall, load_before, load_after, calls=calls, span_s=span_s)
        s.rejected = self.rejection(s)
        return result, s, ref_after


    def measure(self, call: Callable[[], Timed], kernel: ReferenceKernel, accept: Callable[[Any], bool] = bool):
        """Repeat ``call`` under the protocol; a result for which ``accept`` is false (a failed
        answer) stops the repeats.  Raises ``CallFailed`` when the call raises."""
        p, m = self.protocol, self.machine
        samples: list[Sample] = []
        rejected: list[Sample] = []
        started, waited0 = m.wall(), self.waited_s
        ref = kernel.run()
        result, stop, calls = None, "", 0
        while not stop:
            self.wait_for_quiet()
            t0 = m.wall()
            try:
                result, s, ref = self.sample(call, kernel, ref, max(calls, 1))
            except Exception as err:  # the caller classifies the failure
                raise CallFailed(err, m.wall() - t0, samples) from err
            calls = calls or p.calls_for(s.span_s)  # decided by the first call
            if s.rejected and len(rejected) < p.retries and accept(result):
                rejected.append(s)
                continue
            samples.append(s)
            stop = "answer rejected" if not accept(result) else stop_reason(p, samples, m.wall() - started)
        return Measurement(samples, rejected, stop, result, self.waited_s - waited0)


@dataclass
class Task:
    """One task of a round-robin: a name, its call and its kernel; filled with samples."""

    name: str
    call: Callable[[], Timed]
    kernel: ReferenceKernel
    samples: list[Sample] = field(default_factory=list)
    rejected: list[Sample] = field(default_factory=list)
    result: Any = None
    ref: tuple[float, float] | None = None
    stop: str = ""
    accept: Callable[[Any], bool] = lambda result: True  # False: a failed answer, not repeated
    calls: int = 0  # per sample; 0: one, then decided by the first call


def round_robin(timer: Timer, tasks: Sequence[Task], on_sample: Callable[[Task, Sample], None] | None = None):
    """Time the tasks in rounds, one sample of each per round, until each has stopped by the
    protocol (spread, ``max_repeats``; ``budget_s`` counts per task).  A rejected sample is redone
    after the other tasks of the round (at most ``retries`` times per task).  Returns the tasks."""
    p, m = timer.protocol, timer.machine
    budget = {t.name: 0.0 for t in tasks}
    while True:
        queue = [t for t in tasks if not t.stop]
        if not queue:
            return tasks
        k = 0
        while k < len(queue):  # ``queue`` grows while iterating: a rejected sample is redone last
            t, k = queue[k], k + 1
            timer.wait_for_quiet()
            if t.ref is None:
                t.ref = t.kernel.run()
            t0 = m.wall()
            t.result, s, t.ref = timer.sample(t.call, t.kernel, t.ref, max(t.calls, 1))
            t.calls = t.calls or p.calls_for(s.span_s)
            budget[t.name] += m.wall() - t0
            if on_sample is not None:
                on_sample(t, s)
            if s.rejected and len(t.rejected) < p.retries and t.accept(t.result):
                t.rejected.append(s)
                queue.append(t)
                continue
            t.samples.append(s)
            t.stop = stop_reason(p, t.samples, budget[t.name]) if t.accept(t.result) else "answer rejected"


def stop_reason(p: Protocol, samples: Sequence[Sample], used_s: float) -> str:
    """Why a measurement with these accepted ``samples``, ``used_s`` seconds into its budget,
    stops ("" to go on): the budget, the cap, or its last ``min_repeats`` CPU times (the
    quantity reported and ranked) agreeing within ``spread``."""
    if samples and used_s >= p.budget_s:
        return "budget"
    if len(samples) >= p.max_repeats:
        return "max_repeats"
    if len(samples) >= p.min_repeats and spread([x.cpu_s for x in samples[-p.min_repeats :]]) <= p.spread:
        return "spread"
    return ""


def task_summary(timer: Timer, t: Task) -> dict:
    """``Measurement.summary`` of a round-robin task."""
    return Measurement(t.samples, t.rejected, t.stop, t.result).summary(timer.protocol, timer.machine.cores)


SOFTWARE = ("numpy", "scipy", "cvxpy")  # the distributions whose versions a record names, with Python's


def _read(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return ""


def machine_record(
    environ: Mapping[str, str] | None = None,
    cpuinfo: Path = Path("/proc/cpuinfo"),
    product: Path = Path("/sys/class/dmi/id/product_name"),
) -> dict[str, Any]:
    """What a measurement ran on: ``cores`` (``os.cpu_count``), ``usable_cores`` (the affinity
    mask), ``cpu_model`` (``model name`` of ``cpuinfo``; "" unknown), ``hypervisor`` (the CPU's
    ``hypervisor`` flag: the machine is virtualised; None without ``cpuinfo``), ``product`` (the
    firmware's product name, e.g. a hypervisor's; "" unknown), ``threads`` (each of
    ``jobenv.THREAD_VARIABLES`` in ``environ``, default this process's; "" unset) and ``software``
    (Python's version and those of ``SOFTWARE``)."""
    from importlib.metadata import PackageNotFoundError, version

    from signorini.pipeline.jobenv import THREAD_VARIABLES

    environ = os.environ if environ is None else environ
    text = _read(cpuinfo)
    entries = [line.split(":", 1) for line in text.splitlines() if ":" in line]
    model = next((v.strip() for k, v in entries if k.strip() == "model name"), "")
    flags = next((v.split() for k, v in entries if k.strip() == "flags"), None)
    software = {"Python": platform.python_version()}
    for name in SOFTWARE:
        with contextlib.suppress(PackageNotFoundError):
            software[name] = version(name)
    return {
        "cores": os.cpu_count(),
        "usable_cores": usable_cores(),
        "cpu_model": model,
        "hypervisor": None if flags is None else "hypervisor" in flags,
        "product": _read(product).strip(),
        "threads": {name: environ.get(name, "") for name in THREAD_VARIABLES},
        "software": software,
    }
