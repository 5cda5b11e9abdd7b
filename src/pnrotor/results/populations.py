"""The results of populations: `Population` (the states of `pnrotor.evolve_many`) and `PopulationTable` (the states of
a batch table's rows, `pnrotor.batch.population`), with the quantities derived from a state that both give
(:func:`spin_angles`, :class:`SpinAngles`), each registered with its arrays (`pnrotor.results.schema`).
"""

from dataclasses import dataclass, field

import numpy as np

from pnrotor import approximants
from pnrotor.results.schema import ARRAYS, M_UNIT, ROTOR, Array, check, register, short_repr

INSPIRAL_ENDS = ("v_max", "energy_balance", "vdot_nonpositive", "vdot_peak", "vdot_divergent")
"""Terminations that end an inspiral (:mod:`pnrotor.pn.evolve`): a binary integrated to the end of its inspiral
(no target frequency) reached it with one of these; the others (``max_steps``, ``step_underflow``, ``nonfinite``,
``time_limit``, ``spin_magnitude``) stop it before."""

STATE = ("t", "t_seconds", "v", "Phi", "chi1", "chi2", "R", "ell_hat")
"""The fields of a :class:`Population` that hold a state (NaN where the target was not reached)."""
FIELDS = STATE + ("termination", "reached", "message", "nsteps", "nfev")
"""The array fields of a :class:`Population`, one entry per binary (and target): what a :class:`PopulationTable`
keeps, row by row."""


def spin_angles(chi1, chi2, ell_hat, m1, m2):
    r"""θ₁, θ₂, φ₁₂, χ_eff and χ_p of spins ``chi1``, ``chi2`` and orbital direction ``ell_hat`` (arrays (..., 3),
    inertial frame) and masses ``m1``, ``m2`` (broadcast against (...)) → dict of arrays (...):

    * tilts θᵢ = atan2(|χᵢ × ℓ̂|, χᵢ·ℓ̂) ∈ [0, π], the angle between χᵢ and ℓ̂ (NaN where χᵢ = 0);
    * φ₁₂ = atan2(ℓ̂·(χ₁ × χ₂), χ₁·χ₂ − (χ₁·ℓ̂)(χ₂·ℓ̂)) taken in [0, 2π]: the azimuth of χ₂'s projection on the
      orbital plane minus that of χ₁'s, counterclockwise about ℓ̂ (LALSuite's and bilby's ``phi_12``; NaN where a
      projection is zero);
    * χ_eff = (m₁ χ₁·ℓ̂ + m₂ χ₂·ℓ̂)/(m₁ + m₂) (Ajith et al. 2011, PRL 106, 241101, Eq. (1));
    * χ_p = max(χ_A⊥, q (4q + 3)/(4 + 3q) χ_B⊥), A the heavier body, B the lighter, q = m_B/m_A ≤ 1 and χᵢ⊥ =
      |χᵢ × ℓ̂| (Schmidt, Ohme & Hannam 2015, PRD 91, 024043, Eq. (3.4)).
    """
    chi1, chi2, ell_hat = (np.asarray(x, dtype=np.float64) for x in (chi1, chi2, ell_hat))
    m1, m2 = np.asarray(m1, dtype=np.float64), np.asarray(m2, dtype=np.float64)
    along1, along2 = (np.einsum("...i,...i", chi, ell_hat) for chi in (chi1, chi2))
    across1, across2 = (np.linalg.norm(np.cross(chi, ell_hat), axis=-1) for chi in (chi1, chi2))
    with np.errstate(invalid="ignore"):
        theta1, theta2 = (np.where(np.linalg.norm(chi, axis=-1) > 0.0, np.arctan2(across, along), np.nan)
                          for chi, along, across in ((chi1, along1, across1), (chi2, along2, across2)))
        phi12 = np.arctan2(np.einsum("...i,...i", ell_hat, np.cross(chi1, chi2)),
                           np.einsum("...i,...i", chi1, chi2) - along1 * along2)
        phi12 = np.where(across1 * across2 > 0.0, np.where(phi12 < 0.0, phi12 + 2.0 * np.pi, phi12), np.nan)
        heavy = m1 >= m2
        q = np.where(heavy, m2 / m1, m1 / m2)
        chi_p = np.maximum(np.where(heavy, across1, across2),
                           q * (4.0 * q + 3.0) / (4.0 + 3.0 * q) * np.where(heavy, across2, across1))
    return {"theta1": theta1, "theta2": theta2, "phi12": phi12, "chi_eff": (m1 * along1 + m2 * along2) / (m1 + m2),
            "chi_p": chi_p}


class SpinAngles:
    """The derived quantities of :func:`spin_angles` at each state, as properties, and the whole table as a pandas
    DataFrame: shared by :class:`Population` and :class:`PopulationTable` (whose ``inputs`` hold
    ``m1_Msun`` and ``m2_Msun`` per binary)."""

    def derived(self):
        """:func:`spin_angles` of the states (NaN where the target was not reached): dict of (N,) or (N, K)."""
        shape = self.v.shape
        m1, m2 = (self.inputs[key].reshape(self.inputs[key].shape + (1,) * (self.v.ndim - 1))
                  for key in ("m1_Msun", "m2_Msun"))
        return spin_angles(self.chi1, self.chi2, self.ell_hat, np.broadcast_to(m1, shape), np.broadcast_to(m2, shape))

    theta1 = property(lambda self: self.derived()["theta1"], doc="tilt of χ₁ from ℓ̂ (rad; :func:`spin_angles`)")
    theta2 = property(lambda self: self.derived()["theta2"], doc="tilt of χ₂ from ℓ̂ (rad; :func:`spin_angles`)")
    phi12 = property(lambda self: self.derived()["phi12"], doc="φ₁₂ (rad; :func:`spin_angles`)")
    chi_eff = property(lambda self: self.derived()["chi_eff"], doc="χ_eff (:func:`spin_angles`)")
    chi_p = property(lambda self: self.derived()["chi_p"], doc="χ_p (:func:`spin_angles`)")

    def to_pandas(self):
        """A pandas DataFrame of the table, one row per binary (per binary and target with a list of frequencies:
        columns ``binary`` and ``target``): the per-binary inputs (vectors at f_ref as ``chi1_ref_x`` …, a
        target of the list as ``frequency_Hz``), the state (vectors as ``chi1_x`` …, ``R_w`` … ``R_z``),
        ``termination``, ``reached``, ``message``, ``nsteps``, ``nfev``, the derived ``theta1``, ``theta2``,
        ``phi12``, ``chi_eff``, ``chi_p``, and the states where the integrations stopped (``stopped_v`` …); the
        options every binary shares in ``DataFrame.attrs``."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("to_pandas needs pandas: pip install 'pnrotor[pandas]'") from None

        n, shape = len(self), self.v.shape
        columns = {}
        if self.v.ndim == 2:
            columns["binary"], columns["target"] = (x.ravel() for x in np.indices(shape))

        def add(name, x, per_binary=False):
            x = np.asarray(x)
            if per_binary and self.v.ndim == 2:
                x = np.broadcast_to(x.reshape((n, 1) + x.shape[1:]), shape + x.shape[1:])
            x = x.reshape((-1,) + x.shape[len(shape):])
            if x.ndim == 1:
                columns[name] = x
            else:
                for c, axis in zip(x.T, "wxyz" if x.shape[1] == 4 else "xyz"):
                    columns[f"{name}_{axis}"] = c

        if getattr(self, "name", None) is not None:
            add("name", self.name, True)
        shared = {}
        for key, value in self.inputs.items():
            if not (isinstance(value, np.ndarray) and value.shape[:1] == (n,)):
                shared[key] = value
            elif key == "frequencies_Hz":
                add("frequency_Hz", value)
            else:
                add(key + "_ref" * (value.ndim == 2), value, True)
        for key in FIELDS:
            add(key, getattr(self, key))
        for key, value in self.derived().items():
            add(key, value)
        for key in STATE:
            add("stopped_" + key, self.stopped_at[key])
        frame = pd.DataFrame(columns)
        frame.attrs.update(shared)
        return frame


_STATE_ARRAYS = {
    "t": Array(("N",), M_UNIT + "; t = 0 at f_ref"),
    "t_seconds": Array(("N",), "s; t = 0 at f_ref"),
    "v": Array(("N",), "c; PN parameter v = (M Omega_orb)^(1/3)"),
    "Phi": Array(("N",), "rad; orbital phase, 0 at f_ref"),
    "chi1": Array(("N", 3), "1; dimensionless spin S1 / m1^2, inertial-frame components"),
    "chi2": Array(("N", 3), "1; dimensionless spin S2 / m2^2, inertial-frame components"),
    "R": ROTOR,
    "ell_hat": Array(("N", 3), "1; unit normal to the orbital plane, inertial-frame components"),
}
"""The state of a binary in a `PopulationTable`, one per row: at its target, and where its integration stopped."""


@register(arrays={
    "name": Array(("N",), "the row's name (the batch table's name column, or its default name)", "str"),
    **{name: array._replace(units=array.units + "; at the row's target, NaN where reached is false", finite=False)
       for name, array in _STATE_ARRAYS.items()},
    "termination": Array(("N",), "why the integration to this state stopped (f_max, f_min or the end of the "
                         "inspiral, as pnrotor.evolve names it)", "str"),
    "reached": Array(("N",), "whether the integration reached the row's target (f_max, f_min or the end of the "
                     "inspiral)", "bool"),
    **{"stopped_at/" + name: array._replace(finite=False) for name, array in _STATE_ARRAYS.items()},
    "message": Array(("N",), "the termination's explanation", "str"),
    "nsteps": Array(("N",), "step attempts of the integration that gave the state", "int64"),
    "nfev": Array(("N",), "right-hand-side evaluations of that integration", "int64"),
    "inputs/row": Array(("N",), "number of the row in the batch table (1 = the first binary)", "int64"),
    "inputs/m1_Msun": Array(("N",), "Msun"),
    "inputs/m2_Msun": Array(("N",), "Msun"),
    "inputs/chi1": Array(("N", 3), "1; dimensionless spin of body 1 at f_ref, inertial frame"),
    "inputs/chi2": Array(("N", 3), "1; dimensionless spin of body 2 at f_ref, inertial frame"),
    "inputs/f_ref_Hz": Array(("N",), "Hz; GW frequency where the spins are given, t = 0"),
    "inputs/f_min_Hz": Array(("N",), "Hz; the state is the one at this GW frequency, integrated backward "
                             "(NaN: no f_min)", finite=False),
    "inputs/f_max_Hz": Array(("N",), "Hz; the state is the one at this GW frequency (NaN: no f_max; with "
                             "neither, the end of the inspiral)", finite=False),
    "inputs/approximant": Array(("N",), approximants.names(), "str"),
    "inputs/pn_order": Array(("N",), "PN order of the nonspinning terms"),
    "inputs/spin_orbit_order": Array(("N",), "PN order of the spin-orbit terms (-1: none; NaN: pnrotor.evolve's "
                                     "default)", finite=False),
    "inputs/spin_spin_order": Array(("N",), "PN order of the spin-spin terms (-1: none; NaN: pnrotor.evolve's "
                                    "default)", finite=False),
    "inputs/precession": Array(("N",), "spin precession model", "str"),
    "inputs/atol": Array(("N",), "absolute tolerance of the integrator"),
    "inputs/lambda1": Array(("N",), "1; dimensionless tidal deformability of body 1"),
    "inputs/lambda2": Array(("N",), "1; dimensionless tidal deformability of body 2"),
    "inputs/tidal_order": Array(("N",), "PN order of the tidal terms (0, 5 or 6; NaN: pnrotor.evolve's default)",
                                finite=False),
    "inputs/horizon_absorption": Array(("N",), "whether the run followed the flux into the black holes' horizons",
                                       "bool"),
})
@dataclass
class PopulationTable(SpinAngles):
    """The states of a table's rows at their targets (those that succeeded, in the table's order), one entry per row.

    Derived at the states, as for `pnrotor.Population`: ``theta1``, ``theta2``, ``phi12``, ``chi_eff``, ``chi_p``
    (:func:`spin_angles` for the formulas); :meth:`to_pandas` gives the table as a DataFrame.

    Attributes
    ----------
    name : (N,) str — the row's name (its name column, or `pnrotor.batch.table.default_name`)
    t, t_seconds, v, Phi, chi1, chi2, R, ell_hat, termination, reached, message, nsteps, nfev, stopped_at : as in
        `pnrotor.Population` (the state at the target, NaN where ``reached`` is False; why its integration stopped
        and that integration's work; the states where the integrations stopped), (N,), (N, 3) or (N, 4)
    inputs : dict — per row (arrays of N): ``row`` (its number in the table, from 1), ``m1_Msun``,
        ``m2_Msun``, ``chi1``, ``chi2`` (at f_ref), ``f_ref_Hz``, ``f_min_Hz``, ``f_max_Hz`` (NaN where absent),
        ``approximant``, ``pn_order``, ``spin_orbit_order``, ``spin_spin_order`` (NaN: evolve's default),
        ``precession``, ``atol``, ``lambda1``, ``lambda2``, ``tidal_order`` (NaN: evolve's default),
        ``horizon_absorption`` (bool); and the options every row shares (``rtol``, ``rotor``, ...), as
        `Population.inputs` has them
    """

    name: np.ndarray
    t: np.ndarray
    t_seconds: np.ndarray
    v: np.ndarray
    Phi: np.ndarray
    chi1: np.ndarray
    chi2: np.ndarray
    R: np.ndarray
    ell_hat: np.ndarray
    termination: np.ndarray
    reached: np.ndarray
    message: np.ndarray
    nsteps: np.ndarray
    nfev: np.ndarray
    stopped_at: dict
    inputs: dict = field(default_factory=dict)

    __repr__ = short_repr

    @staticmethod
    def upgraded(values, schema):
        """The fields of a table written by an older pnrotor (`pnrotor.hdf5.read`; docs/hdf5-schema.md) in today's
        layout. Tables before horizon absorption have no ``inputs/horizon_absorption``: False. Tables of HDF5 schema 1
        held each row's state where its integration stopped and had no ``reached``, ``stopped_at`` or tidal inputs:
        that state as ``stopped_at``, ``reached`` from its termination as `pnrotor.evolve_many` sets it (f_max or f_min
        for a target frequency, one of :data:`INSPIRAL_ENDS` for the end of the inspiral), NaN states where it is
        False, and no tides (Λ = 0, the tidal order evolve's default)."""
        if not isinstance(values.get("inputs"), dict) or "termination" not in values:
            return values   # not a table's layout: the layout check says what is wrong
        n = np.shape(values["termination"])
        values = dict(values, inputs={"horizon_absorption": np.zeros(n, dtype=bool), **values["inputs"]})
        if schema != 1 or "reached" in values or any(name not in values for name in STATE):
            return values
        inputs = values["inputs"]
        targets = [name for name in ("f_max", "f_min") if name + "_Hz" in inputs]
        has_target = np.any([~np.isnan(np.asarray(inputs[name + "_Hz"], dtype=float)) for name in targets], axis=0)
        termination = np.asarray(values["termination"])
        reached = np.where(has_target, np.isin(termination, ("f_max", "f_min")), np.isin(termination, INSPIRAL_ENDS))
        upgraded = dict(values, reached=reached, stopped_at={name: values[name] for name in STATE},
                        inputs={"lambda1": np.zeros(n), "lambda2": np.zeros(n), "tidal_order": np.full(n, np.nan),
                                **inputs})
        for name in STATE:
            upgraded[name] = np.where(reached.reshape(n + (1,) * (values[name].ndim - 1)), values[name], np.nan)
        return upgraded

    def __len__(self):
        return self.t.shape[0]


@register(arrays={   # the fields it shares with a PopulationTable, with an axis K over a list of targets, NaN allowed
    name: array._replace(shape=("N", "K", *array.shape[1:]), finite=False)
    for name, array in ARRAYS["PopulationTable"].items() if name != "name" and not name.startswith("inputs/")
}, dimensions={"K": lambda values: values["t"].shape[1] if values["t"].ndim == 2 else None}, stored=False)
@dataclass
class Population(SpinAngles):
    """The states of :func:`pnrotor.evolve_many`: row i is binary i, with a second axis k over the target
    frequencies when ``frequencies`` was given.

    The state fields (t … ell_hat) hold the state at the target: the target frequency, or the end of the inspiral
    where there is none.  Where ``reached`` is False they are NaN (an inspiral that ended first, an integration
    stopped by the integrator's limits, or ``'invalid'``), and ``stopped_at`` holds the state where the integration
    stopped.  Derived at the states (properties, :func:`spin_angles` for the formulas): ``theta1``, ``theta2``,
    ``phi12``, ``chi_eff``, ``chi_p``; :meth:`to_pandas` gives them all as one DataFrame.

    Attributes
    ----------
    t : (N,) or (N, K) time of the state in units of each binary's total mass M (t = 0 at f_ref)
    t_seconds : the same in seconds
    v, Phi : PN parameter and orbital phase (Φ = 0 at f_ref)
    chi1, chi2 : (N, 3) or (N, K, 3) dimensionless spins, inertial frame
    R : (N, 4) or (N, K, 4) unit orbital-frame rotor (n̂ = R x̂ R⁻¹, ℓ̂ = R ẑ R⁻¹)
    ell_hat : (N, 3) or (N, K, 3) orbital angular momentum direction
    termination : str — why the integration to that state stopped (:mod:`pnrotor.pn.evolve`): ``'f_max'`` or
        ``'f_min'`` where the target frequency was reached, else why the inspiral ended first, or ``'invalid'``
    reached : bool — whether the integration reached the target: termination ``'f_max'`` or ``'f_min'`` for a
        target frequency, one of :data:`INSPIRAL_ENDS` for the end of the inspiral
    message : str — the termination's message, or the error naming the bad input
    nsteps, nfev : int — the step attempts and right-hand-side evaluations of the integration that gave the
        state (one per binary and direction: the targets of a list share it; with nearer targets it keeps
        dense output, 3 more evaluations per step than a single ``evolve``)
    stopped_at : dict — the state fields (:data:`STATE`) where each integration stopped, reached or not (NaN where
        ``'invalid'``); equal to the state fields where ``reached``
    inputs : dict — the options shared by every binary, and per binary (arrays (N,) or (N, 3)): ``m1_Msun``,
        ``m2_Msun``, ``chi1``, ``chi2`` (at f_ref), ``f_ref_Hz``, ``ell_hat``, ``n_hat``, ``kappa1``, ``kappa2``,
        ``lambda1``, ``lambda2``, and the target, ``f_end_Hz`` (NaN: the end of the inspiral) or ``frequencies_Hz``
        (N, K)
    stats : dict — ``wall_time_s`` of the call and ``wall_time_integrate_s`` of its compiled loops (the rest is
        Python: checks and parameter vectors)

    Checked when built (:func:`pnrotor.results.check`, by ``ARRAYS["Population"]``): a ValueError names every array of
    the wrong type, dtype or shape and every zero rotor.
    """

    t: np.ndarray
    t_seconds: np.ndarray
    v: np.ndarray
    Phi: np.ndarray
    chi1: np.ndarray
    chi2: np.ndarray
    R: np.ndarray
    ell_hat: np.ndarray
    termination: np.ndarray
    reached: np.ndarray
    message: np.ndarray
    nsteps: np.ndarray
    nfev: np.ndarray
    stopped_at: dict
    inputs: dict = field(default_factory=dict)
    stats: dict = field(default_factory=dict)

    __repr__ = short_repr

    def __post_init__(self):
        check(self, "cannot build")   # the arrays' shapes, dtypes and rotors, by ARRAYS["Population"]

    def __len__(self):
        return self.t.shape[0]
