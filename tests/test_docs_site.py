"""The documentation site (issue 26, first increment): it builds with warnings as errors, offline, every
analysis kind has its generated reference page, no internal link or anchor is broken, and every gallery
script runs (sphinx-gallery executes them during the build and aborts on an error; each script asserts its
own error against its reference).

The outputs documented in mechgen.analyses.outputs_doc are checked against what the kinds return for a few
runs: every output a run returns is documented (or is a coordinate / model output, documented as such).
"""
from __future__ import annotations

import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

from mechgen.analyses import option_text, reference
from mechgen.analyses.outputs_doc import OUTPUTS, outputs_of
from mechgen.analyses.registry import get, kinds
from mechgen.symbolic.names import BUILTIN_OUTPUTS

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"

pytest.importorskip("sphinx")
pytest.importorskip("sphinx_gallery")


class Links(HTMLParser):
    """The href/src targets and the ids of one HTML page."""

    def __init__(self):
        super().__init__()
        self.targets: list[str] = []
        self.ids: set[str] = set()

    def handle_starttag(self, tag, attrs):
        for key, value in attrs:
            if key in ("href", "src") and value is not None:
                self.targets.append(value)
            if key in ("id", "name") and value:
                self.ids.add(value)


def parse(page: Path) -> Links:
    links = Links()
    links.feed(page.read_text(encoding="utf-8"))
    return links


def build_site(work: Path) -> Path:
    """The site built from a copy of docs/ (the build writes the generated pages and the gallery into its
    source folder), warnings as errors, with the network unused: no intersphinx, no remote image."""
    source = work / "docs"
    shutil.copytree(DOCS, source, ignore=shutil.ignore_patterns("_build", "auto_examples", "kinds",
                                                               "sg_execution_times.rst"))
    shutil.copy(ROOT / "CHANGELOG.md", work / "CHANGELOG.md")  # docs/changelog.md includes ../CHANGELOG.md
    out = work / "html"
    run = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", str(source),
                          str(out)], capture_output=True, text=True, timeout=600, cwd=work)
    assert run.returncode == 0, run.stdout + run.stderr
    return out


@pytest.mark.slow  # the gallery's scripts: about 140 s
def test_site(tmp_path):
    """One build, then each check of the built site (one test rather than a shared fixture: pytest-xdist would
    build the site once per worker that holds a test needing it)."""
    site = build_site(tmp_path)
    check_every_kind_has_its_generated_page(site)
    check_no_broken_internal_links(site)
    check_no_remote_images(site)
    check_every_gallery_script_ran_and_drew(site)
    check_readme_links_reach_the_site(site)
    check_decorators_page_anchors_every_member(site)


def check_every_kind_has_its_generated_page(site):
    index = (site / "kinds" / "index.html").read_text(encoding="utf-8")
    for kind in kinds():
        page = site / "kinds" / f"{kind}.html"
        assert page.exists(), kind
        text = page.read_text(encoding="utf-8")
        for option in get(kind).schema:  # every scene key the loader accepts is on the page
            assert f">{option}<" in text, (kind, option)
        assert f"{kind}.html" in index


def check_no_broken_internal_links(site):
    """Every relative href/src of every page names a file of the build, and every #fragment an id there."""
    pages = sorted(site.rglob("*.html"))
    assert len(pages) > 20
    ids = {page: parse(page).ids for page in pages}
    broken = []
    for page in pages:
        for target in parse(page).targets:
            parts = urlsplit(target)
            if parts.scheme or target.startswith("//"):  # external (docstrings' tcp://host:port included)
                continue
            path = (page.parent / unquote(parts.path)).resolve() if parts.path else page
            if not path.exists():
                broken.append((page.relative_to(site), target))
            elif parts.fragment and path.suffix == ".html" and unquote(parts.fragment) not in ids.get(path, set()):
                broken.append((page.relative_to(site), target))
    assert not broken, broken


def check_no_remote_images(site):
    """Offline: no page shows an image fetched from the network."""
    for page in site.rglob("*.html"):
        for target in re.findall(r'<img[^>]+src="([^"]+)"', page.read_text(encoding="utf-8")):
            assert not urlsplit(target).scheme, (page, target)


def check_every_gallery_script_ran_and_drew(site):
    """Each docs/examples/plot_*.py has its page with its printed output and at least one figure."""
    scripts = sorted((DOCS / "examples").glob("plot_*.py"))
    assert {f"{stem}.py" for stem in SEED_PAGES + EVERYDAY_PAGES} <= {script.name for script in scripts}
    for script in scripts:
        page = site / "auto_examples" / f"{script.stem}.html"
        text = page.read_text(encoding="utf-8")
        assert "sphx-glr-script-out" in text, script.name  # the captured stdout
        assert re.search(rf'src="[^"]*sphx_glr_{script.stem}_\d+\.png"', text), script.name
        assert "Traceback" not in text, script.name


#: the gallery's pages for everyday work (issue 26, item 2): a model of your own, time histories and phase
#: portraits, mode shapes, a rotor from scratch, hybrid models (the bouncing ball and the impact oscillator)
EVERYDAY_PAGES = ("plot_model_in_five_minutes", "plot_time_history_phase", "plot_mode_shapes", "plot_jeffcott_rotor",
                  "plot_bouncing_ball", "plot_impact_oscillator")

SEED_PAGES = ("plot_balloon_branches", "plot_rotor_campbell_ross", "plot_fpu_recurrence", "plot_rod_large_deflection",
              "plot_impact_restitution", "plot_limestone_penetration", "plot_stick_slip_hysteresis",
              "plot_rate_state_friction", "plot_friction_beam_spectrum")


def check_readme_links_reach_the_site(site):
    """The README's front page links every seed system's gallery page: each relative link names a file of the
    repository or, under docs/_build/html/, a page of the built site (and each seed page is linked)."""
    links = re.findall(r"\]\(([^)#]+)\)", (ROOT / "README.md").read_text(encoding="utf-8"))
    built = "docs/_build/html/"
    for link in links:
        if link.startswith(built):
            assert (site / link[len(built):]).exists(), link
        else:
            assert (ROOT / link).exists(), link
    for stem in SEED_PAGES:
        assert f"docs/examples/{stem}.py" in links and f"{built}auto_examples/{stem}.html" in links, stem


def test_generated_pages_name_every_option_and_output():
    """Without Sphinx: each page holds each schema key with its default, and each documented output."""
    pages = reference.pages()
    assert set(pages) == {"index.rst"} | {f"{k}.rst" for k in kinds()}
    for kind in kinds():
        text = pages[f"{kind}.rst"]
        for name, option in get(kind).schema.items():
            assert f"``{name}``" in text and reference.default_text(option) in text, (kind, name)
        for output in outputs_of(kind):
            assert f"``{output.name}``" in text, (kind, output.name)
    assert {"modes", "stability", "steady", "simulate", "sweep", "campbell"} <= set(OUTPUTS)


def test_docstring_rst_keeps_formulas_literal():
    """A norm's bars are escaped outside literals, an indented formula after a blank line becomes a literal
    block, and a bullet's continuation line stays in its bullet."""
    text = "Title.\n\nThe error |x| and ``a|b``:\n\n    e = |v_r| / v_c\n\n* item\n  continued\n"
    rst = reference.docstring_rst(text)
    assert "The error \\|x\\| and ``a|b``::" in rst
    assert "    e = |v_r| / v_c" in rst
    assert "* item\n  continued" in rst


MODEL = '''\
"""Forced, damped oscillator with a floor: m x'' + c x' + k x = F cos(w t)."""
import sympy as sp
from mechgen import Model, Param

model = Model("docs_outputs_oscillator", doc=__doc__)
model.params(Param("m", 1.0), Param("c", 0.1), Param("k", 4.0), Param("F", 0.5), Param("w", 1.5))
model.coordinates("x")


@model.kinetic
def kinetic(v, p):
    return p.m * v.x**2 / 2


@model.potential
def potential(q, p):
    return p.k * q.x**2 / 2


@model.dissipation
def dissipation(v, p):
    return p.c * v.x**2 / 2


@model.forces
def forces(p, t):
    return {"x": p.F * sp.cos(p.w * t)}


model.output("spring_force", lambda q, p: p.k * q.x, unit="N")
'''


def test_documented_outputs_cover_what_the_kinds_return(tmp_path):
    """Every output modes, stability, steady and simulate return for a forced, damped oscillator is documented
    (a coordinate or a model output counts as the documented ``<output>``)."""
    import mechgen

    (tmp_path / "oscillator.py").write_text(MODEL)
    system = mechgen.compile(str(tmp_path / "oscillator.py"))
    model_names = {"x", "spring_force", *BUILTIN_OUTPUTS}
    results = {"modes": mechgen.modes(system), "stability": mechgen.stability(system),
               "steady": mechgen.steady(system), "simulate": mechgen.simulate(system, t_end=1.0, samples=11)}
    for kind, result in results.items():
        documented = {o.name for o in outputs_of(kind)}
        for key in result.keys():
            assert key in documented or (key in model_names and "<output>" in documented), (kind, key)


def test_example_scene_is_a_shipped_table_of_its_kind():
    """A page's example is an [[analysis]] table of that kind copied from a shipped scene (not an inner one)."""
    text = reference.kind_page("sweep", ROOT / "scenes")
    example = text.split("Example\n-------\n", 1)[1]
    name = re.search(r"``scenes/(\S+)``", example).group(1)
    body = [line[3:] for line in example.splitlines() if line.startswith("   ")]
    assert "\n".join(body) in (ROOT / "scenes" / name).read_text()
    assert 'kind = "sweep"' in body
    assert "Example" not in reference.kind_page("sweep", None)


def test_documented_outputs_cover_a_rotors_modes_sweep_and_campbell():
    """The built-in Laval rotor: modes (damped, with whirl), a sweep of modes and a Campbell diagram return only
    documented outputs (a sweep's inner outputs are the modes' ones)."""
    import mechgen

    rotor = mechgen.compile("laval_rotor")
    modes = {o.name for o in outputs_of("modes")}
    for key in mechgen.modes(rotor).keys():
        assert key in modes, ("modes", key)
    sweep = {o.name for o in outputs_of("sweep")} | modes
    for key in mechgen.sweep(rotor, "modes", {"Omega": [0.0, 100.0]}).keys():
        assert key in sweep, ("sweep", key)
    campbell = {o.name for o in outputs_of("campbell")}
    for key in mechgen.campbell(rotor, over={"Omega": [0.0, 100.0, 200.0]}, count=2).keys():
        assert key in campbell, ("campbell", key)


def test_option_meanings_come_from_the_schema_and_the_module():
    """An option's row holds its Option's ``doc`` and its check's docstring; an Option without a doc falls back
    on the kind docstring's parenthesis about it."""
    from mechgen.analyses.schema import Option, boolean

    text = reference.kind_page("simulate")
    row = text.split("* - ``series``", 1)[1].split("* - ", 1)[0]
    assert "Keep the time history t and trajectory" in row and "true or false" in row
    assert "*Described:*" not in row
    assert reference.option_meaning(Option(boolean), "the time history") == (
        "*Described:* the time history. *Accepts:* true or false.")
    assert reference.described("x ``a`` (b (c) d) e", "a") == "b (c) d"
    assert reference.described("x ``a`` b", "a") == ""
    assert option_text.toml_literal({"a": [1.0, True], "b": "auto"}) == '{ a = [1.0, true], b = "auto" }'


def option_rows(kind: str) -> dict[str, str]:
    """Each scene key's row of the kind's reference page (its cells' text, joined)."""
    text = reference.kind_page(kind).split("Scene keys\n----------\n", 1)[1].split("\nOutputs\n", 1)[0]
    rows = text.split("   * - ")[2:]  # [0]: the directive, [1]: the header row
    return {re.match(r"``(\w+)``", row).group(1): " ".join(row.split()) for row in rows}


def test_every_option_of_every_kind_has_a_doc_shown_on_its_page():
    """No key of a registered kind lands undocumented: each Option has a non-empty ``doc``, and the kind's
    reference page shows it in that key's row (as a sentence, bars escaped)."""
    for kind in kinds():
        schema = get(kind).schema
        rows = option_rows(kind) if schema else {}
        assert set(rows) == set(schema), kind
        for name, option in schema.items():
            assert option.doc.strip(), f"{kind}.{name} has no doc"
            assert reference.escape_bars(reference.sentence(option.doc)) in rows[name], (kind, name)


def test_analysis_functions_list_their_options_and_outputs():
    """``help(mechgen.<kind>)`` shows every option with its doc and default and every output of the kind's
    table (mechgen.analyses.outputs_doc) with its unit: the sources the reference pages use."""
    from mechgen.analyses import public

    for kind in kinds():
        doc = getattr(public, kind).__doc__
        options = doc.split("Options accepted", 1)[1].split("Outputs (", 1)[0]
        outputs = doc.split("Outputs (", 1)[1]
        for name, option in get(kind).schema.items():
            assert f"* ``{name}`` (" in options, (kind, name)
            assert reference.escape_bars(option.doc) in " ".join(options.split()), (kind, name)
        for output in outputs_of(kind):
            assert f"* ``{output.name}``" in outputs, (kind, output.name)
            if output.unit.strip() not in ("", "-"):
                assert f"* ``{output.name}`` [{output.unit}]" in outputs, (kind, output.name)
        assert not re.search(r":\w+:`", outputs), kind  # a role of the pages' own folder breaks elsewhere
    assert option_text.first_sentence("A list, e.g. a pair. Then more.") == "A list, e.g. a pair."


def test_a_dash_cell_renders_as_text_not_as_an_empty_bullet():
    """A unit of "-" (no unit), an empty cell and a cell opening with "- " render, through docutils, as the em
    dash in the table's cell and never as a nested bullet list (the reference pages' tables)."""
    from docutils import nodes
    from docutils.core import publish_doctree

    lines = reference.table(("name", "unit", "meaning"),
                            [("``a``", "-", ""), ("``b``", "- or rad", "x")], "30 30 40")
    tree = publish_doctree("\n".join(lines), settings_overrides={"report_level": 5})
    cells = [entry.astext() for entry in tree.findall(nodes.entry)]
    assert cells == ["name", "unit", "meaning", "a", "\u2014", "\u2014", "b", "\u2014 or rad", "x"]
    assert not [b for b in tree.findall(nodes.bullet_list) if b.parent.tagname == "entry"]
    for kind in kinds():
        assert not re.search(r"^ *- -( |$)", reference.kind_page(kind), re.M), kind


def test_every_kind_a_shipped_scene_uses_shows_an_example_that_loads():
    """A kind whose [[analysis]] table a shipped scene holds has that table on its page, and the scene it comes
    from loads (mechgen.scene.load: the same checks as ``mechgen run``) with an analysis of that name and kind;
    a kind no shipped scene uses says so."""
    from mechgen import models
    from mechgen.scene.info import lookup_model
    from mechgen.scene.load import load_scene, tomllib

    scenes = ROOT / "scenes"
    used = {table["kind"] for path in scenes.glob("*.toml")
            for table in tomllib.loads(path.read_text(encoding="utf-8")).get("analysis", [])}
    loaded = {}
    for kind in kinds():
        page = reference.kind_page(kind, scenes)
        example = page.split("Example\n-------\n", 1)[1]
        if kind not in used:
            assert "No shipped scene uses this kind" in example, kind
            continue
        name = re.search(r"``scenes/(\S+)``", example).group(1)
        table = tomllib.loads("\n".join(line[3:] for line in example.splitlines()
                                         if line.startswith("   ")))["analysis"][0]
        assert table["kind"] == kind, kind
        if name not in loaded:
            loaded[name] = load_scene(str(scenes / name), lookup_model=lookup_model, model_names=models.known)
        specs = {spec.name: spec.kind for spec in loaded[name].analyses}
        assert specs[table["name"]] == kind, (kind, name)


def public_members_of_model() -> list[str]:
    """Every public method and property of mechgen.Model (the model author's declarations and queries)."""
    from mechgen import Model

    return [name for name in dir(Model) if not name.startswith("_")]


def test_decorators_page_documents_every_public_member_of_model():
    """docs/decorators.md pulls each public method and property of Model by autodoc, so a declaration added to
    the class and left off the page fails here (the built page's anchors are checked in test_site)."""
    text = (DOCS / "decorators.md").read_text(encoding="utf-8")
    public = public_members_of_model()
    assert {"kinetic", "whirl_pair", "mode", "rod", "field", "part", "boundary"} <= set(public)
    missing = [name for name in public
               if not re.search(rf"^\.\. auto(method|property):: mechgen\.Model\.{name}$", text, re.M)]
    assert not missing, missing


def check_decorators_page_anchors_every_member(site):
    text = (site / "decorators.html").read_text(encoding="utf-8")
    for name in public_members_of_model():
        assert f'id="mechgen.Model.{name}"' in text, name


def test_decorators_page_examples_declare_models_that_derive():
    """The page's examples run in order in one namespace (the pendulum's block checks its damped frequency and
    its energy loss against closed forms); every model they declare is derived and compiled (numpy backend),
    the string also with its steady and stress-form kernels (only the stress form when inextensible)."""
    import mechgen
    from mechgen.codegen.kernel_names import HAMILTONIAN_KERNELS, STEADY_KERNELS

    text = (DOCS / "decorators.md").read_text(encoding="utf-8")
    namespace, models = {}, []
    for i, block in enumerate(re.findall(r"^```python\n(.*?)^```", text, re.S | re.M)):
        exec(compile(block, f"docs/decorators.md, python block {i + 1}", "exec"), namespace)
        if isinstance(namespace.get("model"), mechgen.Model) and (not models or namespace["model"] is not models[-1]):
            models.append(namespace["model"])
    assert len(models) >= 8
    for model in models:
        system = mechgen.compile(model, backend="numpy")
        assert system.meta["model"] == model.name
    string = models[-1]
    assert string.name == "docs_string"
    mechgen.compile(string, backend="numpy", kernels=STEADY_KERNELS + HAMILTONIAN_KERNELS)
    mechgen.compile(string, {"law": "inextensible"}, backend="numpy", kernels=HAMILTONIAN_KERNELS)  # no V to invert


#: the shipped scenes run to compare what the kinds return with their tables: every kind a shipped scene uses, on
#: each kind of model that uses it (about 25 s in all). Left out as slower and covered by these:
#: balloon_branches and balloon_frequencies (balloon_stability), fpu_large (fpu_recurrence), ross_example_rotor
#: (stepped_rotor), rate_state_stick_slip (rate_state_slider, spring_pendulum), rod_end_torque and rotating_beam
#: (rod_tip_load)
CHEAP_SCENES = ("balloon_stability", "beam_modes", "beck_column", "curved_beam_stiffness", "fpu_chain",
                "fpu_recurrence", "friction_beam", "impact_models", "laval_rotor", "moving_string", "penetration_limestone",
                "rate_state_slider", "rod_dynamics", "rod_tip_load", "rotating_string", "spring_pendulum",
                "stepped_rotor", "stick_slip_element", "timoshenko_modes", "jeffcott_unbalance", "duffing_backbone")

PLACEHOLDER = re.compile(r"<([a-z ]+)>")


def documented_names(kind: str, names: set[str]) -> list[re.Pattern]:
    """One pattern per documented output of ``kind``: a placeholder (``<output>``, ``<parameter>``, ``<alias>``
    ...) stands for one of ``names`` (the scene's model's names and the names its table gives), ``<end>`` for
    start, end, max or min."""
    words = "|".join(re.escape(n) for n in sorted(names, key=len, reverse=True))
    patterns = []
    for output in outputs_of(kind):
        parts = PLACEHOLDER.split(output.name)
        regex = "".join(re.escape(part) if i % 2 == 0 else "(?:start|end|max|min)" if part == "end" else f"(?:{words})"
                        for i, part in enumerate(parts))
        patterns.append(re.compile(regex + r"\Z"))
    return patterns


def names_in(value) -> set[str]:
    """The identifiers an analysis table's option values hold (aliases' names, ``parameters``, ``at`` keys ...)."""
    if isinstance(value, dict):
        return set().union(*(names_in(v) | ({k} if k.isidentifier() else set()) for k, v in value.items()))
    if isinstance(value, list):
        return set().union(*(names_in(v) for v in value)) if value else set()
    return {value} if isinstance(value, str) and value.isidentifier() else set()


def model_names(model) -> set[str]:
    """Every name a model declares or mechgen reports beside its outputs."""
    return ({p.name for p in model.param_list} | set(model.coordinates_all) | set(model.field_names)
            | set(model.output_names) | {o.name for o in model.shape_outputs} | {i.name for i in model.internals}
            | set(BUILTIN_OUTPUTS))


@pytest.mark.parametrize("scene", CHEAP_SCENES)
def test_every_output_a_shipped_scene_returns_is_documented(scene):
    """Each analysis of the scene returns only outputs its kind's table documents (a sweep: its own and its inner
    kind's), a placeholder standing for a name of the model or of the analysis's table; and every kind has its
    table, so no reference page is left pointing at its module docstring."""
    try:
        import tomllib
    except ImportError:  # Python 3.10
        import tomli as tomllib

    import mechgen

    assert set(kinds()) <= set(OUTPUTS)
    path = ROOT / "scenes" / f"{scene}.toml"
    tables = {t["name"]: t for t in tomllib.loads(path.read_text())["analysis"]}
    result = mechgen.run(str(path))
    base = model_names(mechgen.load_model(result["model"]))
    for entry in result["analyses"]:
        table = tables[entry["name"]]
        names = base | set().union(*(names_in(v) for k, v in table.items() if k not in ("name", "kind")))
        patterns = documented_names(entry["kind"], names)
        if entry["kind"] == "sweep":
            patterns += documented_names(table["analysis"]["kind"], names)
        missing = [key for key in entry["outputs"] if not any(p.match(key) for p in patterns)]
        assert not missing, (scene, entry["name"], entry["kind"], missing)


def test_documented_outputs_cover_impact_and_response():
    """The two kinds no shipped scene runs: one impact of the built-in viscoelastic contact (with its curve) and
    the Laval rotor's receptance return only documented outputs."""
    import mechgen

    impact = mechgen.impact(mechgen.compile("viscoelastic_impact"), t_end=50.0, curve=True)
    response = mechgen.response(mechgen.compile("laval_rotor"), input="x", omega=[10.0, 20.0])
    for kind, result in (("impact", impact), ("response", response)):
        documented = {o.name for o in outputs_of(kind)}
        assert set(result.keys()) <= documented, (kind, set(result.keys()) - documented)
