"""Every default figure a reader trusts (issue 26, item 6): the shipped scenes' plots, each checked as it is saved
(tests/figure_audit.py says what a figure must have).

Every shipped scene's figures are audited in tests/test_rerun.py, drawn from the second of its two runs (a scene
run once fewer). Here: the same audit through ``mechgen run --plot`` (the CLI's path, and a plane model's mesh
figure carried beside the results), and the units on a parameter axis.
"""
from __future__ import annotations

from pathlib import Path

import pytest
from figure_audit import audited_savefig

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("scene", ["spring_pendulum", "plane_block_continuation"])
def test_figures_drawn_by_the_cli_are_complete(scene, tmp_path):
    pytest.importorskip("matplotlib")
    from mechgen.cli import main

    with audited_savefig({}) as seen:
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
