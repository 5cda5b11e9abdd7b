"""Benchmark of pnrotor inside the analysis pipelines: the same host calls with ``PNRotorT4`` and with LAL's
``SpinTaylorT4``, same keywords, same run.

For every case (BBH at q = 1, 3, 10, near-extremal spins, NSBH and BNS; nonspinning, aligned, precessing; from
tests/pn_cases.py, f_lower = f_ref = their f_start, Δt = 1/4096 s, ι = 0.7, φ_ref = 0.4, 100 Mpc), at LAL's spin
truncation (``spin_order=6``):

* PyCBC ``get_td_waveform`` at amplitude order 0 and at LAL's highest, 3 (1.5PN; pnrotor's ℓ ≤ 5 then);
* PyCBC ``get_fd_waveform`` at amplitude order 0, δf = 1/(the waveform's duration rounded up to a power of 2).
  PyCBC has no frequency-domain route for SpinTaylorT4: the benchmark registers pnrotor's length estimator for it
  and an end-frequency estimator returning the value pnrotor's gives (computed once, free), so both go through
  PyCBC's ``get_fd_waveform_from_td`` with the same length, sampling and padding; pnrotor's own end-frequency
  estimate (one run to the end, no output) is inside its timings;
* gwsignal ``GenerateTDWaveform`` (condition 0): ``gwsignal_get_waveform_generator("SpinTaylorT4")`` at its only
  amplitude order, 1.5PN, against ``PNRotorGenerator("T4", amplitude_order=3, spin_order=6)``.

Both codes give the same waveform within 2.4e-6 of its peak in every column (tests/test_pipelines_*.py).  Medians
over interleaved rounds (LAL, pnrotor, call by call, case by case), with the range over rounds; the ratios are
LAL / pnrotor of the medians, of wall time and of this process's CPU time (robust on a shared machine, where a
call is often descheduled; it counts both of pnrotor's threads, :mod:`pnrotor.threads`, and LAL's one).  The "waveform" columns are the share of pnrotor's time spent in its one waveform function
(:func:`pnrotor.interop.pipelines.polarizations`: evolve → modes → polarizations), the rest being the host's glue,
conditioning and FFT.

    python benchmarks/bench_pipelines.py [--rounds 7] [--cases NAME ...] [--threads 1]
"""

import argparse
import functools
import math
import os
import statistics
import sys
import time
import warnings

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from pn_cases import CASES as PN_CASES  # noqa: E402

DT = 1.0 / 4096
CASES = dict(PN_CASES, **{"NSBH-aligned": (10, 1.4, [0, 0, 0.6], [0, 0, 0], 20.0),
                          "NSBH-precessing": (10, 1.4, [0.6, 0.0, 0.4], [0.02, 0.0, 0.01], 20.0)})
DEFAULT_CASES = ["equal-nonspinning", "q3-aligned", "q3-precessing", "q10-precessing", "near-extremal-precessing",
                 "NSBH-aligned", "NSBH-precessing", "BNS-nonspinning", "BNS-precessing"]
CALLS = ("td0", "td3", "fd0", "gwsignal")


class Clock:
    """Seconds spent in the wrapped function during the current call."""

    def __init__(self, function):
        self.function, self.spent = function, 0.0

    def __call__(self, *args, **kwargs):
        t = time.perf_counter()
        try:
            return self.function(*args, **kwargs)
        finally:
            self.spent += time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--cases", nargs="+", default=DEFAULT_CASES)
    ap.add_argument("--threads", type=int, help="pnrotor's threads per call (pnrotor.threads.limit; default numba's)")
    args = ap.parse_args()
    warnings.filterwarnings("ignore")
    if args.threads:
        from pnrotor import threads
        threads.limit(args.threads)

    import astropy.units as u
    import pycbc.waveform as waveform
    from lalsimulation.gwsignal import GenerateTDWaveform, gwsignal_get_waveform_generator
    from pycbc.waveform import plugin
    from pycbc.waveform.waveform import _filter_ends

    from pnrotor.interop import pipelines
    from pnrotor.interop import pycbc as pnrotor_pycbc
    from pnrotor.interop.gwsignal import PNRotorGenerator

    clock = Clock(pipelines.polarizations)
    pipelines.polarizations = clock   # the plugins call it through the module
    plugin.add_length_estimator("SpinTaylorT4", functools.partial(pnrotor_pycbc.length_in_time, "PNRotorT4"))
    lal_generator = gwsignal_get_waveform_generator("SpinTaylorT4")
    our_generator = PNRotorGenerator("T4", amplitude_order=3, spin_order=6)

    def keywords(name, **extra):
        m1, m2, c1, c2, f = CASES[name]
        return dict(mass1=m1, mass2=m2, spin1x=c1[0], spin1y=c1[1], spin1z=c1[2], spin2x=c2[0], spin2y=c2[1],
                    spin2z=c2[2], delta_t=DT, f_lower=f, f_ref=f, inclination=0.7, coa_phase=0.4, distance=100.0,
                    spin_order=6, **extra)

    def gwsignal_parameters(name):
        m1, m2, c1, c2, f = CASES[name]
        one = u.dimensionless_unscaled
        return dict(mass1=m1 * u.solMass, mass2=m2 * u.solMass, **{f"spin1{c}": x * one for c, x in zip("xyz", c1)},
                    **{f"spin2{c}": x * one for c, x in zip("xyz", c2)}, deltaT=DT * u.s, f22_start=f * u.Hz,
                    f22_ref=f * u.Hz, phi_ref=0.4 * u.rad, inclination=0.7 * u.rad, distance=100.0 * u.Mpc,
                    condition=0)

    setups = {}
    for name in args.cases:
        td = keywords(name, amplitude_order=0)
        duration = len(waveform.get_td_waveform(approximant="PNRotorT4", **td)[0]) * DT
        fd = dict(td, delta_f=2.0 ** -math.ceil(math.log2(2 * duration)))   # room for PyCBC's 1.5× longer waveform
        f_end = waveform.get_waveform_end_frequency(approximant="PNRotorT4", **fd)
        setups[name] = dict(td0=td, td3=keywords(name, amplitude_order=3), fd0=fd, f_end=f_end,
                            gwsignal=gwsignal_parameters(name), samples=round(duration / DT))

    def call(name, kind, lal):
        s = setups[name]
        if kind == "gwsignal":
            return GenerateTDWaveform(s["gwsignal"], lal_generator if lal else our_generator)
        approximant = "SpinTaylorT4" if lal else "PNRotorT4"
        if kind == "fd0":
            _filter_ends["SpinTaylorT4"] = lambda **params: s["f_end"]
            return waveform.get_fd_waveform(approximant=approximant, **s["fd0"])
        return waveform.get_td_waveform(approximant=approximant, **s[kind])

    times = {(name, kind, who): [] for name in args.cases for kind in CALLS
             for who in ("lal", "ours", "lal cpu", "ours cpu", "waveform")}
    for name in args.cases:   # warm up: compile or load every kernel, fill the caches of the hosts
        for kind in CALLS:
            call(name, kind, True)
            call(name, kind, False)
    for _ in range(args.rounds):
        for name in args.cases:
            for kind in CALLS:
                for lal in (True, False):
                    clock.spent = 0.0
                    cpu, t = time.process_time(), time.perf_counter()
                    call(name, kind, lal)
                    elapsed = time.perf_counter() - t
                    who = "lal" if lal else "ours"
                    times[name, kind, who].append(elapsed)
                    times[name, kind, who + " cpu"].append(time.process_time() - cpu)
                    if not lal:
                        times[name, kind, "waveform"].append(clock.spent / elapsed)

    def median(name, kind, who):
        values = times[name, kind, who]
        return statistics.median(values), min(values), max(values)

    print(f"LAL SpinTaylorT4 and pnrotor PNRotorT4 through PyCBC and gwsignal; dt = 1/4096 s, spin_order 6; "
          f"pnrotor's threads: {args.threads or 'numba default'}; "
          f"median (min-max) of {args.rounds} interleaved rounds in ms; ratio LAL / pnrotor of the medians, of wall "
          f"and of CPU time (this process's, pnrotor's two threads counted); wf: share of pnrotor's wall time in its "
          f"waveform function")
    titles = {"td0": "PyCBC get_td_waveform, amplitude order 0", "td3": "PyCBC get_td_waveform, amplitude order 3",
              "fd0": "PyCBC get_fd_waveform, amplitude order 0", "gwsignal": "gwsignal GenerateTDWaveform, 1.5PN"}
    for kind in CALLS:
        print(f"\n{titles[kind]}")
        print(f"{'case':25s} {'samples':>8s} {'LAL':>22s} {'pnrotor':>22s} {'ratio':>6s} {'cpu':>6s} {'wf':>4s}")
        ratios, cpu_ratios = [], []
        for name in args.cases:
            lal, ours = median(name, kind, "lal"), median(name, kind, "ours")
            ratios.append(lal[0] / ours[0])
            cpu_ratios.append(median(name, kind, "lal cpu")[0] / median(name, kind, "ours cpu")[0])
            print(f"{name:25s} {setups[name]['samples']:8d} {fmt(lal):>22s} {fmt(ours):>22s} {ratios[-1]:6.2f} "
                  f"{cpu_ratios[-1]:6.2f} {100 * median(name, kind, 'waveform')[0]:3.0f}%")
        for what, r in (("wall", ratios), ("cpu", cpu_ratios)):
            print(f"LAL / pnrotor ({what}): median {statistics.median(r):.2f}, min {min(r):.2f}, max {max(r):.2f} "
                  f"(pnrotor faster in {sum(x > 1 for x in r)} of {len(r)} cases)")


def fmt(stats):
    """'median (min-max)' in ms."""
    med, lo, hi = (1e3 * x for x in stats)
    digits = 2 if hi < 10 else 1 if hi < 100 else 0
    return f"{med:.{digits}f} ({lo:.{digits}f}-{hi:.{digits}f})"


if __name__ == "__main__":
    main()
