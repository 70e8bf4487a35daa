"""The catalogue of kernel names: which kernels a model can have (:func:`all_kernels`), without sympy.

A compile request names its kernels before anything is derived (mechgen.pipeline.request_of): this module is
read on every start, cached or not, so it imports the lowering modules' own lists only inside
:func:`all_kernels`.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from mechgen.symbolic.model import Model

#: a continuum's kernels
FIELD_KERNELS = ("residual", "tangent", "linear", "outputs", "energy_rates")
#: kernels of a continuum's steady boundary value problem (mechgen.symbolic.steady)
STEADY_KERNELS = ("bvp_residual", "bvp_tangent", "bvp_outputs")
#: kernels of its Hamiltonian (stress) form, y = (u, n) (mechgen.symbolic.steady.derive_steady_hamiltonian)
HAMILTONIAN_KERNELS = ("hbvp_rates", "hbvp_rates_tangent", "hbvp_outputs")
#: the pseudo-kernel of a hybrid model that asks for the derivatives its saltation matrices need
SALTATION = "saltation"


def all_kernels(model: Model) -> tuple[str, ...]:
    """Every kernel a model can have."""
    from mechgen.codegen.lower_lattice import LATTICE_KERNELS
    from mechgen.codegen.lower_lumped import LUMPED_KERNELS

    if model.is_lattice:
        return LATTICE_KERNELS
    if model.is_field:
        return FIELD_KERNELS
    if model.is_plane:
        from mechgen.codegen.lower_plane import PLANE_KERNELS

        return PLANE_KERNELS
    lumped = tuple(k for k in LUMPED_KERNELS if (k != "section" or model.section_fn is not None)
                   and (k != "rod" or model.rod_spec is not None)
                   and (k != "lagrangian" or not (model.is_hybrid or model.internals)))
    if not model.coordinate_names and not model.internals:  # no state: a section's stiffness, a rod, the outputs
        return tuple(k for k in lumped if k in ("outputs", "section", "rod"))
    if model.is_hybrid:  # the event derivatives of saltation matrices (lower_hybrid)
        lumped = lumped + (SALTATION,)
    if model.internals:  # a model of internal variables only (no coordinate) has no potential force
        return tuple(k for k in lumped if k != "force" or model.coordinate_names)
    return tuple(k for k in lumped if not k.startswith("rates"))
