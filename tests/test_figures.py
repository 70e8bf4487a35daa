"""Every default figure a reader trusts (issue 26, item 6): the shipped scenes' plots, each checked as it is saved.

Each figure must have a title (an axes title or a suptitle); every panel that draws data has both axis labels;
a panel with two or more labelled curves has a legend; no linear axis spans less than 1e-9 of its own magnitude
(an axis scaled to round-off, such as E(t) of a conservative run drawn at its rounding noise, or the real parts
of an undamped spectrum at 1e-15). Every shipped scene with figures is checked (the long ones marked slow); the
two without (cross_section and stability_boundary draw nothing: a 6 x 6 stiffness and a located parameter value
are numbers, which the summary prints) are left out.
"""
from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: the shipped scenes checked here (each runs in a few seconds); together they use every kind that plots
SCENES = ("beam_modes", "beck_column", "fpu_chain", "fpu_recurrence", "friction_beam",
          "impact_models", "laval_rotor", "moving_string", "penetration_limestone", "rod_dynamics", "rod_end_torque",
          "rod_tip_load", "rotating_beam", "rotating_string", "spring_pendulum", "stick_slip_element",
          "timoshenko_modes", "balloon_stability", "rotor_internal_damping", "jeffcott_unbalance",
          "van_der_pol_limit_cycle", "duffing_frequency_response", "duffing_softening", "duffing_backbone",
          "rotor_whirl_limit_cycle", "impact_oscillator_bifurcation", "van_der_pol_from_hopf",
          "belt_stick_slip", "phase_bar", "phase_bar_cubic", "orr_sommerfeld", "js_shear", "js_channel", "js_galerkin",
          "js_fluid", "plane_block_continuation")
#: the shipped scenes that take 7 to 25 s each (the rest of the shipped scenes with figures)
SLOW_SCENES = ("balloon_branches", "balloon_frequencies", "rate_state_stick_slip", "ross_example_rotor",
               "stepped_rotor", "fpu_large")


def _has_data(ax) -> bool:
    return bool(ax.lines or ax.collections or ax.patches or ax.images)


def _labelled(ax) -> int:
    return sum(1 for artist in list(ax.lines) + list(ax.collections)
               if artist.get_label() and not artist.get_label().startswith("_"))


def _round_off(ax) -> list[str]:
    found = []
    for name, lim, scale in (("x", ax.get_xlim(), ax.get_xscale()), ("y", ax.get_ylim(), ax.get_yscale())):
        lo, hi = sorted(lim)
        size = max(abs(lo), abs(hi))
        if scale == "linear" and size > 0 and hi - lo < 1e-9 * size:
            found.append(f"{name} axis spans {hi - lo:.3g} at {size:.6g}")
    return found


def audit(fig) -> list[str]:
    """What a figure lacks (an empty list: nothing)."""
    problems = []
    titles = [ax.get_title() for ax in fig.axes] + [fig._suptitle.get_text() if fig._suptitle is not None else ""]
    axes = [ax for ax in fig.axes if ax.axison and ax.get_label() != "<colorbar>"]  # 3D axes: no axison
    if not any(t.strip() for t in titles):
        problems.append("no title")
    for i, ax in enumerate(axes):
        if not _has_data(ax):
            continue
        xlabel = ax.get_xlabel().strip() or any(other.get_xlabel().strip() for other in axes
                                                 if other is not ax and ax.get_shared_x_axes().joined(ax, other))
        ylabel = ax.get_ylabel().strip() or any(other.get_ylabel().strip() for other in axes
                                                 if other is not ax and ax.get_shared_y_axes().joined(ax, other))
        if not xlabel or not ylabel:  # a shared axis is labelled once (under the last panel, beside the first)
            problems.append(f"panel {i}: axis label missing (x {ax.get_xlabel()!r}, y {ax.get_ylabel()!r})")
        if _labelled(ax) >= 2 and ax.get_legend() is None and not fig.legends:
            problems.append(f"panel {i}: {_labelled(ax)} labelled curves and no legend")
        problems += [f"panel {i}: {p}" for p in _round_off(ax)]
    return problems


@pytest.mark.parametrize("scene", list(SCENES) + [pytest.param(name, marks=pytest.mark.slow) for name in SLOW_SCENES])
def test_shipped_scene_figures_are_complete(scene, tmp_path, monkeypatch):
    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    from mechgen.cli import main

    seen: dict[str, list[str]] = {}
    save = Figure.savefig

    def checked(fig, path, *args, **kwargs):
        seen[Path(path).name] = audit(fig)
        return save(fig, path, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", checked)
    code = main(["run", str(ROOT / "scenes" / f"{scene}.toml"), "--plot", str(tmp_path)])
    assert code == 0
    assert seen, f"{scene} drew no figure"
    assert all(p.stat().st_size > 0 for p in tmp_path.glob("*.png"))
    assert {name: found for name, found in seen.items() if found} == {}


def test_a_parameter_axis_carries_the_parameters_declared_unit(tmp_path, monkeypatch):
    """Beck's column's load sweep: P is declared in N (mechgen/models/follower_column.py), so the axis reads
    "P (N)", from a scene (the JSON's ``units``) and from Python (Result.plot) alike."""
    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    import mechgen
    from mechgen.cli import main

    labels: list[str] = []
    save = Figure.savefig

    def checked(fig, path, *args, **kwargs):
        labels.extend(ax.get_xlabel() for ax in fig.axes)
        return save(fig, path, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", checked)
    assert main(["run", str(ROOT / "scenes" / "beck_column.toml"), "--plot", str(tmp_path / "scene")]) == 0
    assert "P (N)" in labels
    labels.clear()
    system = mechgen.compile("follower_column", {"N": 4}, free=["P"])
    result = mechgen.sweep(system, "stability", grid={"P": {"start": 0.0, "stop": 5.0, "num": 3}})
    result.plot(tmp_path / "python")
    assert "P (N)" in labels
