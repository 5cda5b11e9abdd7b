"""The binaries on which pnrotor is compared with LALSuite (tests/test_pn_lal.py, tests/test_waveform_lal.py,
benchmarks/bench_pn.py): name → (m1, m2 in M☉, χ₁, χ₂, f_start in Hz), BBH at q = 1, 3, 10 (nonspinning,
aligned, precessing), near-extremal spins and BNS."""

CASES = {
    "equal-nonspinning": (10, 10, [0, 0, 0], [0, 0, 0], 20.0),
    "equal-aligned": (10, 10, [0, 0, 0.6], [0, 0, 0.6], 20.0),
    "equal-precessing": (10, 10, [0.4, 0.3, 0.2], [-0.3, 0.1, 0.5], 20.0),
    "q3-nonspinning": (30, 10, [0, 0, 0], [0, 0, 0], 20.0),
    "q3-aligned": (30, 10, [0, 0, 0.5], [0, 0, -0.3], 20.0),
    "q3-precessing": (30, 10, [0.5, 0.1, 0.3], [0, 0.4, -0.2], 20.0),
    "q10-nonspinning": (50, 5, [0, 0, 0], [0, 0, 0], 20.0),
    "q10-aligned": (50, 5, [0, 0, 0.7], [0, 0, 0.2], 20.0),
    "q10-precessing": (50, 5, [0.6, 0.0, 0.4], [0.2, -0.2, 0.1], 20.0),
    "near-extremal-aligned": (30, 10, [0, 0, 0.99], [0, 0, 0.99], 20.0),
    "near-extremal-precessing": (30, 10, [0.7, 0.0, 0.7], [0, 0.99, 0], 20.0),
    "BNS-nonspinning": (1.4, 1.4, [0, 0, 0], [0, 0, 0], 30.0),
    "BNS-aligned": (1.4, 1.3, [0, 0, 0.05], [0, 0, -0.04], 30.0),
    "BNS-precessing": (1.4, 1.3, [0.03, 0.02, 0.03], [0.0, -0.04, 0.01], 30.0),
}
