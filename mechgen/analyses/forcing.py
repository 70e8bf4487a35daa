"""The forcing of a ``response`` analysis: the scene keys ``force``, ``unbalance``, ``over``, ``speed_unit``,
``orbits`` and ``orbit_at``, their checks, and the complex generalized-force amplitudes they give.

A harmonic force pattern (``force``) is a table ``coordinate = amplitude`` or ``coordinate = {amplitude,
phase}``: the generalized force Q_k(t) = A_k cos(omega t + phi_k) on coordinate k (N on a translation, N m on a
rotation; phi_k in degrees, default 0), i.e. the complex amplitude f_k = A_k exp(i phi_k).

An unbalance (``unbalance``) is a mass m (kg) at an eccentricity e (m) from the shaft axis at a disk whose two
translational coordinates (x, y) the table names; with the shaft spinning at Omega (rad/s, counter-clockwise
about z = x cross y) it applies the rotating force

    F_x = m e Omega^2 cos(Omega t + phi),   F_y = m e Omega^2 sin(Omega t + phi),

i.e. f_x = m e Omega^2 exp(i phi), f_y = -i m e Omega^2 exp(i phi) (phi in degrees, default 0: the mass on
the x axis at t = 0). Several unbalances (a list of tables) add up. The driving frequency is the speed, given as
``over = {<speed parameter> = values}`` (the key campbell uses for its speeds).

``speed_unit`` (``rad/s``, ``Hz`` or ``rpm``) is the unit of the numbers written in ``omega``, ``over`` and
``orbit_at``; 1 Hz = 2 pi rad/s, 1 rpm = 2 pi / 60 rad/s.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import schema
from mechgen.scene.values import fail, is_choice, join, listing, param_info, show, type_name

#: rad/s per unit of each ``speed_unit``
SPEED_UNITS = {"rad/s": 1.0, "Hz": 2.0 * np.pi, "rpm": 2.0 * np.pi / 60.0}
#: the keys of one unbalance table
UNBALANCE_KEYS = ("coordinates", "mass", "eccentricity", "phase")


def to_rad_per_s(values, unit: str) -> list[float]:
    """Speeds or frequencies written in ``unit`` (a key of SPEED_UNITS) in rad/s: omega = factor * value."""
    return [float(v) * SPEED_UNITS[unit] for v in values]


def in_unit(values, unit: str) -> list[float]:
    """Speeds or frequencies in rad/s expressed in ``unit``: value = omega / factor."""
    return [float(v) / SPEED_UNITS[unit] for v in values]


def _coordinate(ctx, key: str, value: object) -> str:
    if not isinstance(value, str) or value not in ctx.coordinates:
        raise fail(ctx.file, key, f"unknown coordinate {show(value)}", "one of: " + listing(ctx.coordinates))
    return value


def force_pattern(ctx, key: str, value: object) -> dict[str, dict[str, float]]:
    """{coordinate: {"amplitude": A, "phase": phi (degrees)}} from ``coordinate = A`` or ``{amplitude, phase}``."""
    if not isinstance(value, dict) or not value:
        raise fail(ctx.file, key, f"value is {type_name(value)}" if not isinstance(value, dict) else "empty table",
                   "a table coordinate = amplitude or coordinate = {amplitude = A, phase = degrees}")
    out = {}
    for name, item in value.items():
        sub = join(key, name)
        _coordinate(ctx, sub, name)
        if isinstance(item, dict):
            for extra in item:
                if extra not in ("amplitude", "phase"):
                    raise fail(ctx.file, join(sub, extra), f"unknown key {show(extra)}", "amplitude, phase")
            if "amplitude" not in item:
                raise fail(ctx.file, join(sub, "amplitude"), "missing key 'amplitude'",
                           "{amplitude = A, phase = degrees}")
            out[name] = {"amplitude": schema.number(ctx, join(sub, "amplitude"), item["amplitude"]),
                         "phase": schema.number(ctx, join(sub, "phase"), item.get("phase", 0.0))}
        else:
            out[name] = {"amplitude": schema.number(ctx, sub, item), "phase": 0.0}
    return out


def _pair(ctx, key: str, value: object) -> list[str]:
    """Two different coordinate names."""
    if not isinstance(value, list) or len(value) != 2:
        raise fail(ctx.file, key, f"value is {type_name(value)}" if not isinstance(value, list) else
                   f"{len(value)} names", "two coordinate names [x, y] (the disk's translations)")
    pair = [_coordinate(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1)]
    if pair[0] == pair[1]:
        raise fail(ctx.file, key, f"the same coordinate {show(pair[0])} twice", "two different coordinates")
    return pair


def _one_unbalance(ctx, key: str, value: object) -> dict:
    if not isinstance(value, dict):
        raise fail(ctx.file, key, f"value is {type_name(value)}",
                   "a table {coordinates = [x, y], mass = kg, eccentricity = m, phase = degrees}")
    for extra in value:
        if extra not in UNBALANCE_KEYS:
            raise fail(ctx.file, join(key, extra), f"unknown key {show(extra)}", ", ".join(UNBALANCE_KEYS))
    for needed in UNBALANCE_KEYS[:3]:
        if needed not in value:
            raise fail(ctx.file, join(key, needed), f"missing key '{needed}'",
                       "{coordinates = [x, y], mass = kg, eccentricity = m} (phase optional, degrees)")
    mass = schema.number(ctx, join(key, "mass"), value["mass"])
    ecc = schema.number(ctx, join(key, "eccentricity"), value["eccentricity"])
    for name, v in (("mass", mass), ("eccentricity", ecc)):
        if v < 0:
            raise fail(ctx.file, join(key, name), f"{name} {v:g} is negative", "a number >= 0")
    return {"coordinates": _pair(ctx, join(key, "coordinates"), value["coordinates"]), "mass": mass,
            "eccentricity": ecc, "phase": schema.number(ctx, join(key, "phase"), value.get("phase", 0.0))}


def unbalances(ctx, key: str, value: object) -> list[dict]:
    """One unbalance table, or an array of them: [{coordinates, mass, eccentricity, phase (degrees)}]."""
    if isinstance(value, list):
        if not value:
            raise fail(ctx.file, key, "empty array", "a table or a non-empty array of tables")
        return [_one_unbalance(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1)]
    return [_one_unbalance(ctx, key, value)]


def speed_range(ctx, key: str, value: object) -> dict[str, list[float]]:
    """{parameter: speeds}: one numeric model parameter (the spin speed) and its values (>= 0, in speed_unit)."""
    if not isinstance(value, dict) or len(value) != 1:
        raise fail(ctx.file, key, f"value is {type_name(value)}" if not isinstance(value, dict) else
                   f"{len(value)} entries", "one entry: <speed parameter> = {start, stop, num} or an array")
    (name, item), = value.items()
    sub = join(key, name)
    if is_choice(param_info(ctx.file, sub, ctx.model, name)):
        raise fail(ctx.file, sub, f"parameter {show(name)} is a choice", "a numeric parameter (the spin speed)")
    schema.check_not_derived(ctx, sub, name)
    if isinstance(item, dict):
        values = schema.value_range(ctx, sub, item)
    elif isinstance(item, list) and item:
        values = [schema.number(ctx, f"{sub}[{i}]", v) for i, v in enumerate(item, 1)]
    else:
        raise fail(ctx.file, sub, f"value is {type_name(item)}", "an array of speeds or {start, stop, num}")
    if min(values) < 0:
        raise fail(ctx.file, sub, "a speed is negative", "speeds >= 0 (in speed_unit)")
    return {name: values}


def pairs(ctx, key: str, value: object) -> list[list[str]]:
    """An array of coordinate pairs [[x, y], ...] whose orbits are reported."""
    if not isinstance(value, list) or not value:
        raise fail(ctx.file, key, "empty array" if value == [] else f"value is {type_name(value)}",
                   "an array of pairs [[x, y], ...]")
    return [_pair(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1)]


def speed_values(ctx, key: str, value: object) -> list[float]:
    """A non-empty array of numbers >= 0 (speeds or frequencies, in speed_unit)."""
    if not isinstance(value, list) or not value:
        raise fail(ctx.file, key, "empty array" if value == [] else f"value is {type_name(value)}",
                   "a non-empty array of numbers (speed_unit)")
    values = [schema.number(ctx, f"{key}[{i}]", v) for i, v in enumerate(value, 1)]
    if min(values) < 0:
        raise fail(ctx.file, key, "a value is negative", "numbers >= 0 (speed_unit)")
    return values


def check_forcing(ctx, base: str, options: dict) -> None:
    """Exactly one of ``input``, ``force``, ``unbalance``; ``omega`` with the first two, ``over`` with an
    unbalance (the driving frequency is the speed); the speeds within the speed parameter's bounds in rad/s."""
    given = [k for k in ("input", "force", "unbalance") if k in options]
    if len(given) != 1:
        what = "none of them" if not given else " and ".join(given)
        raise fail(ctx.file, join(base, given[-1] if given else "input"), f"a response takes one forcing, got {what}",
                   "exactly one of: input (a unit force), force (a force pattern), unbalance")
    unit = options.get("speed_unit", "rad/s")
    if given == ["unbalance"]:
        if "omega" in options:
            raise fail(ctx.file, join(base, "omega"), "an unbalance drives at the spin speed: 'omega' and "
                       "'unbalance' together", "no omega; the speeds in over = {<speed parameter> = ...}")
        if "over" not in options:
            raise fail(ctx.file, join(base, "over"), "an unbalance needs the speeds",
                       "over = {<speed parameter> = {start, stop, num}} (a numeric model parameter, the spin speed)")
        _check_speed_bounds(ctx, join(base, "over"), options["over"], unit)
        return
    if "over" in options:
        raise fail(ctx.file, join(base, "over"), f"'over' (a speed range) goes with 'unbalance', not '{given[0]}'",
                   "omega (the driving frequencies) with input or force")
    if "omega" not in options:
        raise fail(ctx.file, join(base, "omega"), f"missing key 'omega' for a response to '{given[0]}'",
                   "driving frequencies (speed_unit): a list or {start, stop, num}")


def _check_speed_bounds(ctx, key: str, over: dict, unit: str) -> None:
    from mechgen.scene.bounds import check_value  # the bounds every value the scene writes meets

    (name, values), = over.items()
    info = param_info(ctx.file, key, ctx.model, name)
    for v in to_rad_per_s(values, unit):
        check_value(ctx.file, join(key, name), name, info, v, ctx.limits)


def unbalance_force(n: int, names, items: list[dict], speed: float) -> np.ndarray:
    """The complex force amplitudes of the unbalances at spin speed ``speed`` (rad/s), N:
    f_x = m e Omega^2 exp(i phi), f_y = -i m e Omega^2 exp(i phi) (module docstring), summed."""
    f = np.zeros(n, dtype=complex)
    for u in items:
        ix, iy = (names.index(c) for c in u["coordinates"])
        with np.errstate(over="ignore", invalid="ignore"):  # an overflow is refused by the solve (not finite)
            size = u["mass"] * u["eccentricity"] * np.float64(speed) ** 2 * np.exp(1j * np.deg2rad(u["phase"]))
            f[ix] += size
            f[iy] += -1j * size
    return f


def pattern_force(n: int, names, pattern: dict) -> np.ndarray:
    """f_k = A_k exp(i phi_k) (phi_k in degrees) for the coordinates of a ``force`` pattern, zero elsewhere."""
    f = np.zeros(n, dtype=complex)
    for name, item in pattern.items():
        f[names.index(name)] = item["amplitude"] * np.exp(1j * np.deg2rad(item["phase"]))
    return f


def orbit_pairs(system, options: dict) -> list[list[str]]:
    """The coordinate pairs whose orbits are reported: ``orbits``; else the unbalances' pairs, or the model's
    whirl pairs (Model.whirl_pair) whose two coordinates a ``force`` pattern drives; else none."""
    if "orbits" in options:
        return [list(p) for p in options["orbits"]]
    found = [list(u["coordinates"]) for u in options.get("unbalance", [])]
    pattern = options.get("force") or {}
    whirl = list(system.metadata.whirl or ())
    found += [[x, y] for x, y in zip(whirl[0::2], whirl[1::2]) if x in pattern and y in pattern]
    out: list[list[str]] = []
    for p in found:
        if p not in out:
            out.append(p)
    return out
