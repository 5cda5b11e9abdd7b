"""PyCBC waveform plugin: the time-domain approximants ``PNRotorT1``, ``PNRotorT4``, ``PNRotorT5``.

Registered by pnrotor's entry points (groups ``pycbc.waveform.td``, ``pycbc.waveform.length`` and
``pycbc.waveform.end_freq``), which ``import pycbc.waveform`` loads (``pycbc.waveform.plugin.retrieve_waveform_plugins``),
so that with pnrotor installed (``pip install 'pnrotor[pycbc]'``) and no import of pnrotor::

    hp, hc = pycbc.waveform.get_td_waveform(approximant="PNRotorT4", mass1=30, mass2=10, spin1x=0.5, ...,
                                            delta_t=1/4096, f_lower=20, f_ref=25, inclination=0.7,
                                            coa_phase=0.4, distance=100)
    hp, hc = pycbc.waveform.get_fd_waveform(approximant="PNRotorT4", delta_f=1/16, ...)

The keywords mean what they mean for PyCBC's ``SpinTaylorT4`` (LAL's ChooseTDWaveform), ``coa_phase`` being LAL's
φ_ref and ``long_asc_nodes`` its Ω (:mod:`pnrotor.interop.pipelines`); pnrotor's options (``ell_max``,
``pn_order``, ``atol``, …) pass through as keywords.  The frequency domain is PyCBC's own route from the time domain
(``get_fd_waveform_from_td``: a longer waveform from a lower f_lower, its new start tapered, padded to 1/delta_f,
FFT), which needs the length estimator (PyCBC's TaylorF2 chirp time, as for its SpinTaylorT5) and uses the end
frequency (:func:`end_frequency`) for its sampling.  That route sets f_ref to f_lower whatever is given (PyCBC
2.11 tests for a key ``'f_fref'``).

Tides: ``lambda1``, ``lambda2`` and ``tidal_order`` (LAL's tideO) as for SpinTaylorT4
(:mod:`pnrotor.interop.pipelines`).  Bad input raises PyCBC's ``FailedWaveformError`` with pnrotor's message; so do
unmodelled physics with a non-default value (eccentricity, octupolar tides and f-modes, testing-GR parameters,
mode_array, frame_axis, modes_choice, numrel_data) and keywords that are neither PyCBC's parameters nor pnrotor's
options.  Importing this module is cheap (PyCBC loads it at ``import pycbc.waveform``): numba and pnrotor's PN code
are imported at the first waveform.
"""

import functools
import numbers

from pnrotor.interop import pipelines

__all__ = ["td_waveform", "length_in_time", "end_frequency", "APPROXIMANTS"]

APPROXIMANTS = {f"PNRotor{a}": a for a in pipelines.APPROXIMANTS}

UNMODELLED = {"eccentricity": (0.0,), "mean_per_ano": (0.0,), "modes_choice": (0,), "mode_array": (None,),
              "numrel_data": ("", None), "frame_axis": (0, 2),
              **{key: (None, 0.0) for key in ("lambda_octu1", "lambda_octu2", "quadfmode1", "quadfmode2", "octufmode1",
                                              "octufmode2")}}
"""PyCBC parameters of physics or options pnrotor does not model, with the values that leave them out (frame_axis 0
is PyCBC's "LAL's default", 2 that default, ORBITAL_L, named); the testing-GR parameters (dchi0 …, dalpha1 …,
dbeta1 …) must be 0."""


def _leaves_out(value, allowed):
    """Whether ``value`` is one of ``allowed`` (numbers and text compared by value; a list or array never is)."""
    return any(value is a or (a is not None and isinstance(value, (numbers.Number, str)) and value == a)
               for a in allowed)


SPINTAYLOR = ("amplitude_order", "phase_order", "spin_order", "tidal_order", "dquad_mon1", "dquad_mon2", "lambda1",
              "lambda2")
"""PyCBC's keywords that :func:`pnrotor.interop.pipelines.arguments` maps."""


@functools.cache
def _pycbc_parameters():
    """The names of PyCBC's waveform and location parameters (``pycbc.waveform.parameters``)."""
    from pycbc.waveform import parameters

    return frozenset(str(p) for p in vars(parameters).values() if isinstance(p, parameters.Parameter))


def _split(name, params):
    """(binary keywords of :func:`pnrotor.interop.pipelines.spintaylor_polarizations`, SpinTaylor and pnrotor
    keywords) from PyCBC's ``params``; a ValueError for a non-default unmodelled parameter or an unknown keyword."""
    for key, allowed in UNMODELLED.items():
        value = params.get(key, allowed[0])
        if not _leaves_out(value, allowed):
            raise ValueError(f"{key} = {value!r}: {name} does not model it (leave it at {allowed[0]!r})")
    for key, value in params.items():
        if key.startswith(("dchi", "dalpha", "dbeta")) and value:
            raise ValueError(f"{key} = {value!r}: {name} has no testing-GR deformations (leave it at 0)")
    options = {key: params[key] for key in SPINTAYLOR if key in params}
    pipeline_options = pipelines.evolve_options() | {"ell_max"}
    known = _pycbc_parameters()
    for key, value in params.items():
        if key in pipeline_options:
            options[key] = value
        elif key not in known:
            raise ValueError(f"unknown keyword {key!r}: neither a PyCBC waveform parameter nor a pnrotor option "
                             f"({', '.join(sorted(pipeline_options))})")
    if params.get("mass1") is None or params.get("mass2") is None:
        raise ValueError(f"{name} needs mass1 and mass2")
    binary = dict(m1=params["mass1"], m2=params["mass2"],
                  chi1=[params.get(f"spin1{c}", 0.0) for c in "xyz"], chi2=[params.get(f"spin2{c}", 0.0) for c in "xyz"],
                  f_lower=params.get("f_lower"), f_ref=params.get("f_ref", 0.0))
    return binary, options


def _failed(name, error):
    from pycbc.waveform.waveform import FailedWaveformError

    return FailedWaveformError(f"{name}: {error}")


def td_waveform(name, **params):
    """(h₊, h×) as ``pycbc.types.TimeSeries`` of the approximant ``name`` (one of :data:`APPROXIMANTS`) for PyCBC's
    keywords ``params`` (module docstring)."""
    import numpy as np
    from pycbc.types import TimeSeries

    try:
        binary, options = _split(name, params)
        epoch, hp, hc = pipelines.spintaylor_polarizations(
            APPROXIMANTS[name], **binary, distance=params.get("distance", 1.0),
            inclination=params.get("inclination", 0.0), phi_ref=params.get("coa_phase", 0.0),
            long_asc_nodes=params.get("long_asc_nodes", 0.0), delta_t=params.get("delta_t"), **options)
    except (ValueError, TypeError) as error:
        raise _failed(name, error) from None
    delta_t = float(params["delta_t"])
    return tuple(TimeSeries(np.ascontiguousarray(h, dtype=np.float64), delta_t=delta_t, epoch=epoch, copy=False)
                 for h in (hp, hc))   # arrays of their own: no copy


FLOOR = 1024.0
"""Hz: the end frequency PyCBC's sampling for the frequency domain assumes without an estimate (Δt = 1/2048 s)."""


def end_frequency(name, **params):
    """PyCBC's end-frequency estimate of the approximant ``name``, which sets the sampling of its frequency-domain
    route (Δt = 1/(2 × the next power of 2)): that of the highest harmonic at the end of the inspiral
    (:func:`pnrotor.interop.pipelines.end_frequency`), or :data:`FLOOR` if lower, so that the sampling is never
    coarser than PyCBC's default (the inspiral's abrupt end aliases more, the closer the Nyquist frequency)."""
    try:
        binary, options = _split(name, params)
        return max(FLOOR, pipelines.end_frequency(APPROXIMANTS[name], binary.pop("m1"), binary.pop("m2"),
                                                  binary.pop("chi1"), binary.pop("chi2"), **binary, **options))
    except (ValueError, TypeError) as error:
        raise _failed(name, error) from None


def length_in_time(name, **params):
    """PyCBC's length estimate in s of the approximant ``name`` for its frequency-domain route: TaylorF2's 3.5PN chirp
    time from f_lower, what PyCBC uses for SpinTaylorT5, at 3.5PN whatever ``phase_order`` (PyCBC's estimate is 0 at
    phase_order 0)."""
    from pycbc.waveform.spa_tmplt import spa_length_in_time

    from pnrotor.pn.settings import masses_and_frequencies

    try:
        masses_and_frequencies(params.get("mass1"), params.get("mass2"), params.get("f_lower"), None, None)
    except ValueError as error:
        raise _failed(name, error.args[0].replace("f_ref", "f_lower")) from None
    return spa_length_in_time(**dict(params, phase_order=7))


td_t1, td_t4, td_t5 = (functools.partial(td_waveform, name) for name in APPROXIMANTS)
length_t1, length_t4, length_t5 = (functools.partial(length_in_time, name) for name in APPROXIMANTS)
end_t1, end_t4, end_t5 = (functools.partial(end_frequency, name) for name in APPROXIMANTS)
