"""The one exception for bad input: the CLI prints it as one line and exits 2."""


class InputError(ValueError):
    """Bad user input: the message names the field and the allowed range."""


def check_range(name: str, value: float, lo: float | None = None, hi: float | None = None,
                unit: str = "", lo_open: bool = False) -> float:
    """Return ``value`` as float if finite and inside [lo, hi]; raise InputError naming ``name``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {value!r}") from None
    u = f" {unit}" if unit else ""
    lo_s = "-inf" if lo is None else f"{lo:g}"
    hi_s = "inf" if hi is None else f"{hi:g}"
    bracket = "(" if lo_open else "["
    if (v != v or v in (float("inf"), float("-inf"))
            or (lo is not None and (v < lo or (lo_open and v == lo)))
            or (hi is not None and v > hi)):
        raise InputError(f"{name} = {value!r}{u} is outside the allowed range {bracket}{lo_s}, {hi_s}]{u}")
    return v
