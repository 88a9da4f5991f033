"""sysid: system identification for vibration and motion engineers.

The same library as the ``sysid`` command line, from NumPy: arrays in (samples in
rows, one column per channel; 1-D for one channel), arrays and :class:`Model`
objects out. A Model writes and reads the command line's model files byte for
byte (``Model.to_json``, ``Model.write``, :func:`read_model`) and becomes a
python-control system with ``Model.to_control()``.

Example::

    import sysid
    u, y, Ts = sysid.read_log("par2_gu.csv", inputs=["u"], outputs=["y"])
    model = sysid.n4sid(u, y, Ts, order=4)
    fit, y_hat = sysid.compare(model, u, y)

Errors: :class:`DataError` (a ValueError) for bad data or files, naming
file:line:column; :class:`NumericalError` (a RuntimeError) when a computation
cannot be trusted (rank deficiency, no convergence); ValueError for bad options.
Long computations release the GIL.
"""

from ._sysid import (
    DataError,
    FemModel,
    Markov,
    Model,
    NumericalError,
    __version__,
    ar,
    arma,
    armax,
    arx,
    check,
    chirp,
    compare,
    diagnose,
    era,
    family,
    fem_frf,
    fem_modes,
    fem_reduce,
    filter,
    fit_percent,
    frf,
    hsv,
    lms,
    model_from_json,
    multisine,
    n4sid,
    oe,
    okid,
    prbs,
    psd,
    read_family,
    read_fem,
    read_log,
    read_markov,
    read_model,
    reduce,
    resid,
    stabilization_diagram,
)


def moesp(u, y, Ts, **options):
    """:func:`n4sid` with the MOESP weighting (``method="moesp"``)."""
    return n4sid(u, y, Ts, method="moesp", **options)


def cva(u, y, Ts, **options):
    """:func:`n4sid` with the CVA weighting (``method="cva"``)."""
    return n4sid(u, y, Ts, method="cva", **options)


__all__ = [
    "DataError", "FemModel", "Markov", "Model", "NumericalError", "__version__", "ar", "arma", "armax", "arx", "check", "chirp", "compare",
    "cva", "diagnose", "era", "family", "fem_frf", "fem_modes", "fem_reduce", "filter", "fit_percent", "frf", "hsv", "lms", "model_from_json", "moesp", "multisine", "n4sid",
    "oe", "okid", "prbs", "psd", "read_family", "read_fem", "read_log", "read_markov", "read_model", "reduce", "resid",
    "stabilization_diagram",
]
