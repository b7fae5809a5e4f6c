"""The timing protocol (``signorini.timing``) on a fake machine: a sample under a load above the
cores is rejected and redone later, reference units cancel a uniform slowdown, the repeats stop on
a small spread, at the cap or at the budget; the record of the machine a measurement ran on."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from signorini import timing
from signorini.pipeline.jobenv import THREAD_VARIABLES

OMP, OPENBLAS = THREAD_VARIABLES[0], THREAD_VARIABLES[2]  # two of the variables jobenv names


class FakeMachine(timing.Machine):
    """A machine whose clocks advance only by the work done: ``work(seconds)`` advances the CPU
    clock by ``seconds × slowdown`` and the wall clock by that over the CPU share; the load is
    read from a script (one value per reading, the last repeated)."""

    def __init__(self, loads=(0.5,), slowdown=1.0, share=1.0, cores=2):
        super().__init__(lambda: self.t_wall, lambda: self.t_cpu, self._load, self._sleep, cores)
        self.t_wall = self.t_cpu = 0.0
        self.loads, self.slowdown, self.share, self.slept = list(loads), slowdown, share, 0.0

    def _load(self) -> float:
        return self.loads.pop(0) if len(self.loads) > 1 else self.loads[0]

    def _sleep(self, s: float) -> None:
        self.slept += s
        self.t_wall += s

    def work(self, seconds: float) -> None:
        self.t_cpu += seconds * self.slowdown
        self.t_wall += seconds * self.slowdown / self.share


class FakeKernel:
    """A reference kernel of 0.1 s of work on the fake machine."""

    def __init__(self, machine: FakeMachine):
        self.machine = machine
        self.description = "fake"

    def run(self):
        w0, c0 = self.machine.wall(), self.machine.cpu()
        self.machine.work(0.1)
        return self.machine.wall() - w0, self.machine.cpu() - c0


def solver(machine: FakeMachine, seconds: float):
    def call():
        machine.work(seconds)
        return "answer", None

    return call


FAST = timing.Protocol(
    min_repeats=3, max_repeats=5, spread=0.05, budget_s=100.0, retries=2, wait_s=5.0, poll_s=1.0, min_sample_s=0.0
)


def test_a_sample_under_a_load_above_the_cores_is_redone():
    """Readings before/after each call: the first sample sees load 5 on 2 cores; it is rejected,
    the timer waits for the load to fall, and the measurement is redone: 3 accepted samples."""
    m = FakeMachine(loads=[0.5, 5.0, 5.0, 0.5])
    measured = timing.Timer(FAST, m).measure(solver(m, 0.2), FakeKernel(m))
    assert len(measured.rejected) == 1 and measured.rejected[0].rejected == "load 5.00 > 2"
    assert len(measured.samples) == 3 and not any(s.rejected for s in measured.samples)
    assert measured.waited_s == 0.0  # the load had fallen when the redo started
    summary = measured.summary(FAST, 2)
    assert summary["rejected"] == 1 and not summary["loaded"] and summary["time_stop"] == "spread"
    assert summary["time_s"] == pytest.approx(0.2) and summary["time_ref"] == pytest.approx(2.0)


def test_a_lasting_load_is_waited_for_then_accepted_and_flagged():
    """A load that never falls: bounded waits (``wait_s`` per redo), ``retries`` redos, then the
    samples are accepted and the record says ``loaded``."""
    m = FakeMachine(loads=[8.0])
    measured = timing.Timer(FAST, m).measure(solver(m, 0.2), FakeKernel(m))
    assert len(measured.rejected) == FAST.retries and len(measured.samples) == 3
    assert m.slept == pytest.approx(FAST.wait_s * (FAST.retries + 3))  # every sample waited its bound
    summary = measured.summary(FAST, 2)
    assert summary["loaded"] and summary["load1"] == 8.0 and summary["rejected"] == FAST.retries


def test_a_low_cpu_share_is_rejected():
    m = FakeMachine(share=0.5)
    measured = timing.Timer(FAST, m).measure(solver(m, 0.2), FakeKernel(m))
    assert measured.rejected and measured.rejected[0].rejected.startswith("CPU share 0.50")
    assert measured.summary(FAST, 2)["cpu_share"] == pytest.approx(0.5)


def test_reference_units_cancel_a_uniform_slowdown():
    """A machine 2.3× slower (contention: CPU time grows) and time-shared (CPU share 0.95):
    seconds change, reference units and ratios do not."""
    protocol = timing.Protocol(max_load=100.0, min_cpu_share=0.5)
    out = {}
    for slowdown, share in ((1.0, 1.0), (2.3, 0.95)):
        m = FakeMachine(slowdown=slowdown, share=share)
        t = timing.Timer(protocol, m)
        out[slowdown] = [t.measure(solver(m, s), FakeKernel(m)).summary(protocol, 2) for s in (0.3, 1.2)]
    quiet, slow = out[1.0], out[2.3]
    assert slow[0]["time_s"] == pytest.approx(2.3 * quiet[0]["time_s"])
    assert slow[0]["wall_s"] == pytest.approx(2.3 / 0.95 * quiet[0]["wall_s"])
    for q, s in zip(quiet, slow, strict=True):
        assert s["time_ref"] == pytest.approx(q["time_ref"]) and s["wall_ref"] == pytest.approx(q["wall_ref"])
    assert slow[1]["time_ref"] / slow[0]["time_ref"] == pytest.approx(4.0)


def test_repeats_stop_at_the_cap_and_at_the_budget():
    m = FakeMachine()
    noisy = iter([0.1, 0.2, 0.1, 0.2, 0.1, 0.2, 0.1])

    def call():
        m.work(next(noisy))
        return "answer", None

    measured = timing.Timer(FAST, m).measure(call, FakeKernel(m))
    assert len(measured.samples) == FAST.max_repeats and measured.stop == "max_repeats"
    assert measured.summary(FAST, 2)["spread"] == pytest.approx(1.0)  # CPU times .1 .2 .1 .2 .1
    m = FakeMachine()
    long = timing.Protocol(budget_s=1.0)
    measured = timing.Timer(long, m).measure(solver(m, 3.0), FakeKernel(m))
    assert len(measured.samples) == 1 and measured.stop == "budget"


def test_the_repeats_stop_when_the_cpu_times_agree_whatever_the_kernel_does():
    """The spread that stops the repeats is that of the CPU times the study ranks by: a call of
    constant cost stops after ``min_repeats`` samples though the kernel beside it, and with it
    the reference units, changes from sample to sample."""
    m = FakeMachine()
    kernel_work = iter([0.1, 0.1, 0.3, 0.3] * 10)  # means around the samples .1 .2 .3

    class NoisyKernel(FakeKernel):
        def run(self):
            w0, c0 = self.machine.wall(), self.machine.cpu()
            self.machine.work(next(kernel_work))
            return self.machine.wall() - w0, self.machine.cpu() - c0

    measured = timing.Timer(FAST, m).measure(solver(m, 0.2), NoisyKernel(m))
    assert measured.stop == "spread" and len(measured.samples) == FAST.min_repeats
    assert timing.spread([s.ref_units for s in measured.samples]) > FAST.spread


def test_a_failed_answer_stops_and_an_exception_is_carried():
    m = FakeMachine(loads=[9.0])
    measured = timing.Timer(FAST, m).measure(solver(m, 0.2), FakeKernel(m), accept=lambda r: False)
    assert len(measured.samples) == 1 and not measured.rejected and measured.stop == "answer rejected"

    def boom():
        m.work(0.5)
        raise RuntimeError("diverged")

    with pytest.raises(timing.CallFailed) as err:
        timing.Timer(FAST, FakeMachine()).measure(boom, FakeKernel(m))
    assert str(err.value.error) == "diverged" and err.value.samples == []


def test_a_callee_that_times_itself():
    """A peer's driver times its own solve: (wall, CPU) returned by the call replace the outer clocks."""
    m = FakeMachine()

    def call():
        m.work(1.0)  # interpreter start, imports, set-up: not the solve
        return "answer", (0.25, 0.24)

    measured = timing.Timer(FAST, m).measure(call, FakeKernel(m))
    assert measured.summary(FAST, 2)["time_s"] == pytest.approx(0.24)
    assert measured.summary(FAST, 2)["cpu_share"] == pytest.approx(0.96)


def test_round_robin_redoes_a_rejected_sample_after_the_others():
    m = FakeMachine()
    order = []
    kernel = FakeKernel(m)
    rejected_once = {"b"}

    def task(name, seconds):
        def call():
            m.work(seconds)
            # the load reading after b's first call is high: b's sample is rejected
            m.loads = [9.0, 0.5] if name in rejected_once else [0.5]
            rejected_once.discard(name)
            return name, None

        return timing.Task(name, call, kernel)

    tasks = [task("a", 0.2), task("b", 0.4), task("c", 0.3)]
    timing.round_robin(timing.Timer(FAST, m), tasks, on_sample=lambda t, s: order.append((t.name, bool(s.rejected))))
    assert order[:4] == [("a", False), ("b", True), ("c", False), ("b", False)]
    for t in tasks:
        assert len(t.samples) == 3 and t.stop == "spread"
    summary = timing.task_summary(timing.Timer(FAST, m), tasks[1])
    assert summary["rejected"] == 1 and summary["time_ref"] == pytest.approx(4.0)


def test_protocol_from_mapping_and_the_reference_kernel():
    assert timing.Protocol.from_mapping({"retries": 0}).retries == 0
    with pytest.raises(ValueError, match="unknown keys"):
        timing.Protocol.from_mapping({"retry": 1})
    n = 400
    A = sp.diags([-np.ones(n - 1), 4 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1], format="csr")
    kernel = timing.ReferenceKernel(A, matvecs=5)
    wall, cpu = kernel.run()
    assert wall > 0 and cpu >= 0 and kernel.description.endswith("5 CSR products), n = 400")
    assert kernel.repeats == 50  # a small system's kernel is repeated up to 20 000 unknowns
    assert timing.spread([1.0, 1.1, 0.9]) == pytest.approx(0.2) and timing.spread([1.0]) == 0.0


def test_a_short_call_is_batched_to_last_min_sample_s():
    """The first run of a 0.2 s call decides 5 calls per later sample (``min_sample_s`` = 1 s);
    the times stay per call.  A self-timed call is batched by its whole duration: a peer whose
    solve takes 0.05 s but whose run lasts 1 s is run once per sample."""
    protocol = timing.Protocol(**{**FAST.as_dict(), "min_sample_s": 1.0})
    m, runs = FakeMachine(), []

    def call():
        runs.append(1)
        m.work(0.2)
        return "answer", None

    measured = timing.Timer(protocol, m).measure(call, FakeKernel(m))
    assert [s.calls for s in measured.samples] == [1, 5, 5] and len(runs) == 11
    summary = measured.summary(protocol, 2)
    assert summary["calls"] == 5 and summary["time_s"] == pytest.approx(0.2)
    assert summary["time_ref"] == pytest.approx(2.0)

    def peer():
        m.work(1.0)
        return "answer", (0.05, 0.05)

    measured = timing.Timer(protocol, m).measure(peer, FakeKernel(m))
    assert [s.calls for s in measured.samples] == [1, 1, 1]
    assert measured.summary(protocol, 2)["time_s"] == pytest.approx(0.05)
    assert protocol.calls_for(1e-9) == timing.MAX_CALLS


def test_round_robin_batches_each_task_by_its_own_first_run():
    protocol = timing.Protocol(**{**FAST.as_dict(), "min_sample_s": 1.0})
    m = FakeMachine()
    kernel = FakeKernel(m)
    tasks = [timing.Task("short", solver(m, 0.25), kernel), timing.Task("long", solver(m, 2.0), kernel)]
    timing.round_robin(timing.Timer(protocol, m), tasks)
    assert [s.calls for s in tasks[0].samples] == [1, 4, 4] and [s.calls for s in tasks[1].samples] == [1, 1, 1]
    assert timing.task_summary(timing.Timer(protocol, m), tasks[0])["time_s"] == pytest.approx(0.25)


def test_the_machine_record_reads_the_cpu_the_hypervisor_flag_and_the_threads(tmp_path):
    cpuinfo = tmp_path / "cpuinfo"
    cpuinfo.write_text("processor\t: 0\nmodel name\t: AMD EPYC\nflags\t\t: fpu sse2 hypervisor\n", encoding="utf-8")
    product = tmp_path / "product_name"
    product.write_text("KVM\n", encoding="utf-8")
    record = timing.machine_record({OMP: "1"}, cpuinfo, product)
    assert (record["cpu_model"], record["hypervisor"], record["product"]) == ("AMD EPYC", True, "KVM")
    assert record["threads"][OMP] == "1" and record["threads"][OPENBLAS] == ""
    cpuinfo.write_text("model name\t: Xeon\nflags\t\t: fpu sse2\n", encoding="utf-8")
    assert timing.machine_record({}, cpuinfo, tmp_path / "missing")["hypervisor"] is False
    unknown = timing.machine_record({}, tmp_path / "missing", tmp_path / "missing")
    assert (unknown["cpu_model"], unknown["hypervisor"], unknown["product"]) == ("", None, "")
