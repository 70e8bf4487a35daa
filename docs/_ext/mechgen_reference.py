"""Sphinx extension: write the analysis kinds' reference pages (mechgen.analyses.reference) before reading.

Each kind's page takes its example from the shipped scenes beside the package (a checkout). The pages go to
``<srcdir>/kinds/`` (not committed: .gitignore); a page is rewritten only when its text changed, so an
incremental build re-reads only what changed.
"""
from __future__ import annotations

from pathlib import Path


def write_pages(app) -> None:
    """Write every generated page into the source folder (builder-inited)."""
    import mechgen
    from mechgen.analyses.reference import FOLDER, pages

    folder = Path(app.srcdir) / FOLDER
    folder.mkdir(exist_ok=True)
    scenes = Path(mechgen.__file__).resolve().parents[1] / "scenes"  # the checkout's shipped scenes, if any
    texts = pages(scenes if scenes.is_dir() else None)
    for stale in folder.glob("*.rst"):
        if stale.name not in texts:
            stale.unlink()
    for name, text in texts.items():
        path = folder / name
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")


def setup(app):
    app.connect("builder-inited", write_pages)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
