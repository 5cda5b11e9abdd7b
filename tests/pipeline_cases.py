"""Binaries on which pnrotor's pipeline plugins are compared with LAL's SpinTaylorT4 through the hosts
(tests/test_pipelines_*.py): precessing and nonprecessing BBH, NSBH and BNS, tidal NSBH and BNS, with the host's
keywords."""

DT = 1.0 / 4096
DISTANCE_MPC = 100.0

CASES = {   # m1, m2 (M☉), χ₁, χ₂, f_lower, f_ref (0: f_lower) in Hz, inclination, φ_ref, long_asc_nodes in rad
    "BBH-aligned": (30, 10, [0, 0, 0.5], [0, 0, -0.3], 20.0, 0.0, 0.7, 0.4, 0.0),
    "BBH-precessing": (30, 10, [0.5, 0.1, 0.3], [0, 0.4, -0.2], 20.0, 25.0, 1.1, 2.3, 0.9),
    "NSBH-aligned": (10, 1.4, [0, 0, 0.6], [0, 0, 0], 30.0, 30.0, 2.0, 1.0, 0.0),
    "NSBH-precessing": (10, 1.4, [0.6, 0.0, 0.4], [0.02, 0.0, 0.01], 30.0, 40.0, 2.0, 5.0, 0.3),
    "BNS-nonspinning": (1.4, 1.3, [0, 0, 0], [0, 0, 0], 40.0, 0.0, 0.3, 0.2, 0.0),
    "BNS-precessing": (1.4, 1.3, [0.03, 0.02, 0.03], [0.0, -0.04, 0.01], 40.0, 50.0, 2.6, 4.0, 1.2),
    "NSBH-tidal": (6, 1.3, [0.3, 0.0, 0.4], [0.02, 0.0, 0.01], 30.0, 40.0, 2.0, 5.0, 0.3),
    "BNS-tidal": (1.4, 1.3, [0.03, 0.02, 0.03], [0.0, -0.04, 0.01], 40.0, 50.0, 1.0, 0.5, 0.4),
}
TIDES = {"NSBH-tidal": (0.0, 800.0), "BNS-tidal": (400.0, 600.0)}
"""The cases' tidal deformabilities Λ₁, Λ₂ (LAL's lambda1, lambda2); 0 for the others."""


def pycbc_keywords(case, **extra):
    """PyCBC's keywords of ``case`` at LAL SpinTaylorT4's spin truncation (spin_order 6)."""
    m1, m2, c1, c2, f_lower, f_ref, inclination, phase, nodes = CASES[case]
    return {**dict(mass1=m1, mass2=m2, spin1x=c1[0], spin1y=c1[1], spin1z=c1[2], spin2x=c2[0], spin2y=c2[1],
                   spin2z=c2[2], delta_t=DT, f_lower=f_lower, f_ref=f_ref, inclination=inclination, coa_phase=phase,
                   long_asc_nodes=nodes, distance=DISTANCE_MPC, spin_order=6),
            **dict(zip(("lambda1", "lambda2"), TIDES.get(case, ()))), **extra}


def gwsignal_parameters(case, **extra):
    """gwsignal's parameters (astropy Quantities) of ``case``."""
    import astropy.units as u

    m1, m2, c1, c2, f_lower, f_ref, inclination, phase, nodes = CASES[case]
    one = u.dimensionless_unscaled
    return {**dict(mass1=m1 * u.solMass, mass2=m2 * u.solMass, **{f"spin1{c}": x * one for c, x in zip("xyz", c1)},
                   **{f"spin2{c}": x * one for c, x in zip("xyz", c2)}, deltaT=DT * u.s, f22_start=f_lower * u.Hz,
                   f22_ref=f_ref * u.Hz, phi_ref=phase * u.rad, inclination=inclination * u.rad,
                   longAscNodes=nodes * u.rad, distance=DISTANCE_MPC * u.Mpc, condition=0),
            **{key: x * one for key, x in zip(("lambda1", "lambda2"), TIDES.get(case, ()))}, **extra}
