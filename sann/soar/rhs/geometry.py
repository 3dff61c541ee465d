"""Positions and headings on a map (the kernel's robot functions): ``haversine``, the
``extrapolate-*`` positions, ``compute-heading``, ``compute-range`` and
``round-off-heading``, each to the kernel's last bit (its own values of pi included).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from sann.soar.errors import SoarRuntimeError
from sann.soar.memory import Symbol
from sann.soar.rhs.arithmetic import rounded
from sann.soar.rhs.context import RhsContext, RhsFunction, c_int64, four, int64, kernel_number
from sann.soar.text import format_symbol

#: The kernel's pi for ``haversine`` and the ``extrapolate-*`` functions: with ``math.pi``
#: 5 of 63 measured distances differ in the last digits, with 3.141592653589 none do.
_GEO_PI = 3.141592653589


_EARTH_KM = 6371.0


def _haversine(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """``(haversine lat1 lon1 lat2 lon2)``: the great-circle distance in km between two
    points given in degrees, computed as the kernel does to the last bit (63 cases)."""
    lat1, lon1, lat2, lon2 = (_geo_number(a) for a in four("haversine", args))
    rad = _GEO_PI / 180
    phi1, phi2 = lat1 * rad, lat2 * rad
    half_lat = math.sin((phi2 - phi1) / 2)
    half_lon = math.sin((lon2 * rad - lon1 * rad) / 2)
    a = half_lat * half_lat + math.cos(phi1) * math.cos(phi2) * half_lon * half_lon
    return _EARTH_KM * (2 * math.atan2(math.sqrt(a), math.sqrt(1 - a)))


def _geo_number(value: Symbol) -> float:
    if type(value) is int or type(value) is float:
        return float(value)  # type: ignore[arg-type]
    raise SoarRuntimeError(f"non int/float ({format_symbol(value)}) passed to haversine function.")


def _extrapolate(name: str, trig: Callable[[float], float]) -> RhsFunction:
    """``(extrapolate-x-position x heading speed time)`` and its ``y`` twin: where a thing
    at ``x`` moving ``speed`` along ``heading`` (degrees clockwise from +y) is after
    ``time``. All measured: integers only; ``speed * time`` wraps at 64 bits, the move is
    rounded to a C ``int`` (out of range: -2147483648), then added with 64-bit wrapping;
    y grows downwards: the move along cos(heading) is subtracted (``(extrapolate-y-position
    10 0 5 2)`` is 0, and a move out of range makes y 2147483648 more)."""
    sign = -1 if name == "extrapolate-y-position" else 1

    def call(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
        start, heading, speed, time_ = (_whole(name, a) for a in four(name, args))
        distance = float(int64(speed * time_)) * trig(heading * _GEO_PI / 180)
        return int64(start + sign * _c_int32(math.floor(distance + 0.5)))

    return call


def _whole(name: str, value: Symbol) -> int:
    if type(value) is int:
        return value  # type: ignore[return-value]
    raise SoarRuntimeError(f"non int({format_symbol(value)}) passed to {name} function.")


def _c_int32(value: float) -> int:
    """C's ``(int)`` of a double on x86: out of range or NaN gives -2147483648."""
    if math.isfinite(value) and -(2.0**31) <= value < 2.0**31:
        return int(value)
    return -(1 << 31)


#: The kernel's value of pi for headings: with ``math.pi``, 32 of 316 measured headings
#: differ; with 3.14159 none do (``(compute-heading 0 0 1 1)`` is 44).
_HEADING_PI = 3.14159


def _coordinates(name: str, args: Sequence[Symbol]) -> list[int | float]:
    if len(args) != 4:
        raise SoarRuntimeError(f"'{name}' takes exactly 4 arguments.")
    return [kernel_number(name, a) for a in args]


def _compute_heading(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """Degrees clockwise from +y of the way from (x1, y1) to (x2, y2), in (-180, 180],
    truncated; the coordinates are truncated to integers first (all as the kernel does:
    ``(compute-heading 3 -0.5 2 1)`` is -45, ``(compute-heading 0 0 0 -1)`` is -179)."""
    x1, y1, x2, y2 = (c_int64(v) for v in _coordinates("compute-heading", args))
    heading = math.atan2(y2 - y1, x2 - x1) - _HEADING_PI / 2
    if heading < 0.0:
        heading += 2 * _HEADING_PI
    heading = 2 * _HEADING_PI - heading
    if heading > _HEADING_PI:
        heading -= 2 * _HEADING_PI
    return c_int64(heading * 180 / _HEADING_PI)


def _compute_range(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """The distance from (x1, y1) to (x2, y2), in floating point, truncated to an integer."""
    x1, y1, x2, y2 = (float(v) for v in _coordinates("compute-range", args))
    dx, dy = x2 - x1, y2 - y1
    return c_int64(math.sqrt(dx * dx + dy * dy))


def _round_off_heading(ctx: RhsContext, args: Sequence[Symbol]) -> Symbol:
    """``round-off``, then brought into (-180, 180] (measured: ``(round-off-heading 175 10)``
    is 180, ``(round-off-heading -175 10)`` 180, ``(round-off-heading 185 10)`` -170). The
    kernel crashes on a zero integer precision; we report it as ``round-off`` does."""
    return _heading_range(rounded("round-off-heading", args))


def _heading_range(value: int | float) -> int | float:
    """The kernel's loops ``while h > 180: h -= 360``, ``while h <= -180: h += 360``, with one
    exact remainder (a loop would take forever on 1e18); a multiple of 360 ends as +0."""
    if -180 < value <= 180:
        return value
    if type(value) is float:
        rest: int | float = math.fmod(value, 360.0) + 0.0  # + 0.0 turns -0.0 into 0.0
    else:
        rest = value % 360  # exact for integers of any size
    if rest > 180:
        return rest - 360
    if rest <= -180:
        return rest + 360
    return rest


#: This family's functions, by the name a rule calls them with.
FUNCTIONS: dict[str, RhsFunction] = {
    "haversine": _haversine,
    "extrapolate-x-position": _extrapolate("extrapolate-x-position", math.sin),
    "extrapolate-y-position": _extrapolate("extrapolate-y-position", math.cos),
    "compute-heading": _compute_heading,
    "compute-range": _compute_range,
    "round-off-heading": _round_off_heading,
}
