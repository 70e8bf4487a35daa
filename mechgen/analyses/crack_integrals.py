"""``crack_integrals``: J, K_I, K_II, the T-stress, M, L and Bueckner's integrals of a plane elastic steady state.

The steady state (``about`` an earlier ``steady`` of the scene, else solved here as ``steady`` does) is sampled
at the quadrature points of the mesh: u, grad u and the stress dV/d(grad u) from the model's own kernel. Each
integral is taken in its domain (q-function) form, ``I = - int F_l q_{,l} dA`` over a ring (mechgen.runtime.plane
.integrals), q interpolated from its nodal values q = clip((r_out - r)/(r_out - r_in), 0, 1) by the element's
own shape functions, so that the identity with the contour form is exact for the discrete q.

Scene keys: ``tips`` ([[x, y, angle], ...]: each tip's position (m) and the direction of its crack's extension
(rad from the x axis; expressions of the parameters, ``pi``); ``rings`` ([[r_in, r_out], ...] about each tip, m);
``crack_rings`` ([[r_in, r_out], ...] about ``center``, enclosing the whole crack); ``center`` ([x, y], default
the origin). Outputs, per tip in the order of ``tips`` on the first ring: ``J`` (J_1 in the tip's frame, N/m),
``K_I``, ``K_II`` (interaction integral with the Williams K fields, Pa m^0.5), ``T_stress`` (Kfouri's
point-force field, Pa), ``bueckner_K_I``, ``bueckner_K_II`` (Bueckner's r^-3/2 field, Pa m^0.5); about the whole
crack on the first crack ring: ``M`` (N), ``L`` (N, about ``center``) and ``bueckner`` (Betti's integral with the
Griffith field's rigid-rotation derivative, Shi, Liu & Li's supplemental field: 2 L when the crack is
Griffith's; N); and ``contours``, the path-independence table: every output on every contour, {``rings``,
``J``, ``K_I``, ... (one list per ring, one value per tip), ``crack_rings``, ``M``, ``L``, ``bueckner`` (one value
per crack ring)}. The material is the model's ``mu`` (or ``E``), ``nu`` and ``plane``.
A model with a body force is refused (these forms hold without one), as is a ring that leaves the mesh.
"""
from __future__ import annotations

import numpy as np

from mechgen.analyses import plane_states, schema, summary
from mechgen.analyses.registry import AnalysisKind, register
from mechgen.errors import InputError, SceneError
from mechgen.scene.values import fail, type_name


def _pairs(ctx, key: str, value: object, width: int) -> list[list[float]]:
    if not isinstance(value, list) or not value or not all(isinstance(v, list) and len(v) == width for v in value):
        raise fail(ctx.file, key, f"value is {type_name(value)}", f"a list of [{', '.join(['v'] * width)}] entries")
    return [[schema.number(ctx, f"{key}[{i}][{j}]", x) for j, x in enumerate(v)] for i, v in enumerate(value)]


def tips(ctx, key: str, value: object) -> list[list[float]]:
    """[[x, y, angle], ...]: tip positions (m) and their crack's extension direction (rad)."""
    return _pairs(ctx, key, value, 3)


def rings(ctx, key: str, value: object) -> list[list[float]]:
    """[[r_in, r_out], ...] with 0 < r_in < r_out (m)."""
    out = _pairs(ctx, key, value, 2)
    for i, (r_in, r_out) in enumerate(out):
        if not 0 < r_in < r_out:
            raise fail(ctx.file, f"{key}[{i}]", f"ring [{r_in:g}, {r_out:g}] is not 0 < r_in < r_out", "0 < r_in < r_out")
    return out


SCHEMA = {
    "about": schema.Option(schema.about, doc="an earlier steady analysis whose state is integrated (left out: "
                           "the steady state is solved here)"),
    "tips": schema.Option(tips, schema.REQUIRED, "[[x, y, angle], ...]",
                          doc="each crack tip's position (m) and its crack's extension angle from the x axis (rad)"),
    "rings": schema.Option(rings, schema.REQUIRED, "[[r_in, r_out], ...]",
                           doc="the domain rings about each tip, inner and outer radius (m)"),
    "crack_rings": schema.Option(rings, doc="rings about center that enclose the whole crack, for M, L and "
                                 "the whole-crack Bueckner integral (m)"),
    "center": schema.Option(plane_states.point, [0.0, 0.0], doc="the centre of crack_rings and the origin of M and L (m)"),
}


def needs(options: dict, *, internal: bool) -> set[str]:
    """Residual (stresses at the points) and tangent (the steady solve)."""
    return {"residual", "tangent", "outputs"}


def material(system):
    """closed_forms.PlaneElastic of the model's parameters mu (or E), nu and its plane choice."""
    from mechgen.runtime.plane.closed_forms import PlaneElastic

    values = {**system.fixed, **dict(zip(system.meta.get("params", []), map(float, system.params)))}
    plane = system.selections.get("plane")
    if "nu" not in values or not ("mu" in values or "E" in values) or plane not in ("stress", "strain"):
        raise InputError(f"model {system.meta.get('model')} has no parameters nu and mu (or E) and no choice "
                         "plane = 'stress' | 'strain': the auxiliary fields need its material", key="kind",
                         expected="a plane elastic model with parameters mu or E, nu and the choice plane")
    nu = float(values["nu"])
    E = float(values["E"]) if "E" in values else 2 * float(values["mu"]) * (1 + nu)
    return PlaneElastic(E, nu, plane)


def require_linear_law(system, q) -> None:
    """InputError unless the stress is linear in the displacement gradient at this state (sigma(2 u) = 2 sigma(u)
    at every quadrature point, to 1e-9): the interaction and Bueckner integrals pair the state with linear-elastic
    auxiliary fields, so a finite-strain law's K would be wrong, not approximate."""
    once = system.quadrature_state(q)["stress"]
    twice = system.quadrature_state(2 * np.asarray(q))["stress"]
    if np.abs(twice - 2 * once).max() > 1e-9 * max(float(np.abs(twice).max()), 1e-300):
        raise InputError(f"model {system.meta.get('model')}'s stress is not linear in the displacement gradient: "
                         "K, T and Bueckner's integrals here assume linear elasticity", key="kind",
                         expected="a linear elastic plane model (plane_materials.linear_elastic)")


def state_of(system, options: dict, context: dict) -> np.ndarray:
    """The state to integrate: an earlier steady's, else a steady solve here."""
    if options.get("about"):
        earlier = context.get(options["about"], {})
        if "_q" not in earlier:
            raise SceneError(f"about = {options['about']!r} names no steady state of this scene", key="about",
                             expected="the name of an earlier steady analysis")
        return np.asarray(earlier["_q"])
    return plane_states.plane_steady(system, {})["_q"]


def ring_sample(system, q, center, ring):
    """integrals.Sample of the elements the ring's q crosses: x, w, u, grad u, stress, q, grad q."""
    from mechgen.runtime.plane.integrals import Sample

    data = system.quadrature_state(q)
    mesh = system.mesh
    r = np.hypot(*(mesh.points - np.asarray(center, float)).T)
    q_nodes = np.clip((ring[1] - r) / (ring[1] - ring[0]), 0.0, 1.0)
    local = q_nodes[mesh.cells]
    crossed = np.flatnonzero(local.max(axis=1) > local.min(axis=1))
    if r.max() < ring[1] or not crossed.size:
        raise InputError(f"the ring [{ring[0]:g}, {ring[1]:g}] about ({center[0]:g}, {center[1]:g}) leaves the mesh",
                         key="rings", expected="rings inside the domain")
    N, dN = data["N"], data["dN"][crossed]
    qe = local[crossed]
    return Sample(x=data["x"][crossed], w=data["w"][crossed], grad_q=np.einsum("egld,el->egd", dN, qe),
                  grad_u=data["grad_u"][crossed], stress=data["stress"][crossed], u=data["u"][crossed],
                  q=np.einsum("gl,el->eg", N, qe))


def tip_values(system, q, tip, ring, mat) -> dict:
    """J, K_I, K_II, T and Bueckner's K_I, K_II at one tip on one ring."""
    from mechgen.runtime.plane import integrals
    from mechgen.runtime.plane.closed_forms import CrackTip

    crack_tip = CrackTip((tip[0], tip[1]), tip[2])
    s = ring_sample(system, q, tip[:2], ring)
    K_I, K_II = integrals.stress_intensity(s, crack_tip, mat)
    return {"J": float(integrals.j_vector(s, crack_tip)[0]), "K_I": float(K_I), "K_II": float(K_II),
            "T_stress": float(integrals.t_stress(s, crack_tip, mat)),
            "bueckner_K_I": integrals.bueckner_integral(s, crack_tip, mat, "I"),
            "bueckner_K_II": integrals.bueckner_integral(s, crack_tip, mat, "II")}


def crack_values(system, q, center, ring, mat, crack) -> dict:
    """M, L (about center) and the whole-crack Bueckner integral with the rotation field, on one ring."""
    from mechgen.runtime.plane import integrals
    from mechgen.runtime.plane.closed_forms import griffith_rotation_field

    s = ring_sample(system, q, center, ring)
    aux = griffith_rotation_field(s.x[..., 0], s.x[..., 1], crack, mat)
    flux = integrals.bueckner_flux(s.u, s.stress, aux.u, aux.stress)
    return {"M": integrals.m_integral(s, center), "L": integrals.l_integral(s, center),
            "bueckner": float(integrals.domain_integral(flux, s.w, s.grad_q))}


def griffith_of(system):
    """The Griffith crack whose rotation field is the whole-crack Bueckner integral's auxiliary field."""
    from mechgen.runtime.plane.closed_forms import GriffithCrack

    values = {**system.fixed, **dict(zip(system.meta.get("params", []), map(float, system.params)))}
    return GriffithCrack(float(values["a"]), float(values.get("sigma11", 0.0)), float(values.get("sigma22", 0.0)),
                         float(values.get("sigma12", 0.0)))


def run_crack_integrals(system, options: dict, context: dict) -> dict:
    """The integrals on every ring; the headline values are the first ring's."""
    if not getattr(system, "is_plane", False) or len(system.info["fields"]) != 2:
        raise InputError(f"crack_integrals needs a plane elastic model with a displacement (ux, uy); model "
                         f"{system.meta.get('model')} is not one", key="kind", expected="a plane model such as cracked_plate")
    mat = material(system)
    q = state_of(system, options, context)
    system.require_no_body_force(q)
    require_linear_law(system, q)
    per_ring = [[tip_values(system, q, tip, ring, mat) for tip in options["tips"]] for ring in options["rings"]]
    out = {name: [v[name] for v in per_ring[0]] for name in per_ring[0][0]}
    contours = {"rings": [list(r) for r in options["rings"]],
                **{name: [[v[name] for v in values] for values in per_ring] for name in per_ring[0][0]}}
    if options.get("crack_rings"):
        crack = griffith_of(system)
        center = options.get("center", [0.0, 0.0])
        reach = max(float(np.hypot(tip[0] - center[0], tip[1] - center[1])) for tip in options["tips"])
        inner = min(ring[0] for ring in options["crack_rings"])
        if inner <= reach:
            raise SceneError(f"a crack ring's inner radius {inner:g} does not enclose the crack (its tips reach "
                             f"{reach:g} from the center): it cuts the crack", key="crack_rings",
                             expected=f"rings about center with r_in > {reach:g}")
        whole = [crack_values(system, q, center, ring, mat, crack) for ring in options["crack_rings"]]
        out.update(whole[0])
        contours["crack_rings"] = [list(r) for r in options["crack_rings"]]
        contours.update({name: [values[name] for values in whole] for name in whole[0]})
    out["contours"] = contours
    return out


register(AnalysisKind("crack_integrals", SCHEMA, run_crack_integrals, needs, summary.lines))
