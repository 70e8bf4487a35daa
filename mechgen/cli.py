"""Command line: ``mechgen models | show MODEL_OR_PATH | run SCENE | regen [--check] | bench | export MODEL_OR_PATH``.

Exit code 0 on success, 2 on bad input (one paragraph on stderr, no traceback),
1 when a computation fails (convergence, kernel error) with its message.
"""
from __future__ import annotations

import argparse
import json
import os
import stat
import sys
import tempfile
from pathlib import Path

from mechgen.errors import InputError, MechgenError, file_kind


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="mechgen", description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--version", action="version", version=_version_line())
    sub = ap.add_subparsers(dest="command", required=True)
    sub.add_parser("models", help="list the built-in models and those installed packages register")
    show = sub.add_parser("show", help="print a model's derived equations and matrices")
    show.add_argument("model", help="a model name, a path to a model file, or package.module:attribute")
    run = sub.add_parser("run", help="run a scene file")
    run.add_argument("scene")
    run.add_argument("--set", dest="overrides", action="append", default=[], metavar="NAME=VALUE")
    run.add_argument("--backend", choices=None)
    run.add_argument("--json", dest="json_path")
    run.add_argument("--plot", dest="plot_dir")
    run.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                     help="run the analyses with executor = \"dask\" on this running Dask scheduler (it is trusted "
                          "to run code in this process; a scene file cannot name one)")
    regen = sub.add_parser("regen", help="rewrite mechgen/generated for the built-in models")
    regen.add_argument("--check", action="store_true", help="fail if mechgen/generated is stale")
    bench = sub.add_parser("bench", help="run the benchmarks")
    bench.add_argument("models", nargs="*", help="suites to run (names: mechgen bench --list; default: all)")
    bench.add_argument("--list", dest="list_suites", action="store_true", help="name the suites and exit")
    bench.add_argument("--out", default="bench-out")
    bench.add_argument("--quick", action="store_true")
    export = sub.add_parser("export", help="write a model's kernels as standalone C or CasADi Functions")
    export.add_argument("model", help="a built-in name, a path to a model file, or package.module:attribute")
    export.add_argument("--backend", required=True, help="c (header and source) or casadi (Function.save files)")
    export.add_argument("--out", dest="out_dir", required=True, metavar="DIR", help="folder to write into")
    export.add_argument("--set", dest="overrides", action="append", default=[], metavar="NAME=VALUE",
                        help="fold a parameter value into the code (others stay inputs)")
    export.add_argument("--kernels", default=None, metavar="K1,K2", help="kernels to export (default: all)")
    return ap


def _version_line() -> str:
    """``mechgen 0.1.0 (python 3.11.7, numpy ..., scipy ..., sympy ..., casadi ...)``."""
    from mechgen.version import versions

    found = versions()
    return f"mechgen {found.pop('mechgen')} (" + ", ".join(f"{k} {v}" for k, v in found.items()) + ")"


class _Parser(argparse.ArgumentParser):
    pass


def _existing_parent(path: Path) -> Path:
    """The nearest ancestor of ``path`` that exists (the folder mkdir would create the rest in)."""
    for parent in path.absolute().parents:
        if os.path.lexists(parent):
            return parent
    return Path(path.absolute().anchor)


def check_output(flag: str, path: str, *, folder: bool) -> None:
    """Refuse an output path that cannot be written, before anything is computed: ``--json FILE``
    must not be a folder, ``--plot DIR`` not a file, and the nearest existing ancestor of either
    must be a writable folder (a file there, ``afile/x.json``, cannot be a folder). An existing
    ``--json`` target must be a regular file (or a link, which is replaced, never followed): a
    device, FIFO or socket is refused, never replaced; a name longer than the file system allows is
    refused at the flag."""
    target = Path(path)
    what = "a folder to write the plots into" if folder else "a path for the JSON file"
    if not path:
        raise InputError("the path is empty", key=flag, expected=what)
    check_name_lengths(flag, path, what)
    if folder and target.exists() and not target.is_dir():
        raise InputError(f"{path} exists and is not a folder", key=flag, expected=what)
    if not folder and target.is_dir():
        raise InputError(f"{path} is a folder", key=flag, expected=what + " (a file name, such as results.json)")
    if not folder:
        check_replaceable(flag, target, what)
    if folder and target.is_dir():
        base = target
    else:
        base = _existing_parent(target)
        if not base.is_dir():
            raise InputError(f"{base} is not a folder, so {path} cannot be created", key=flag, expected=what)
    if not os.access(base, os.W_OK | os.X_OK):
        raise InputError(f"the folder {base} is not writable", key=flag, expected=what)


def check_name_lengths(flag: str, path: str, what: str) -> None:
    """Refuse a path with a name longer than NAME_MAX (255 bytes on Linux) or longer than PATH_MAX as a whole,
    at the flag (an OSError "File name too long" otherwise, after the computation)."""
    base = _existing_parent(Path(path))
    try:
        name_max, path_max = os.pathconf(base, "PC_NAME_MAX"), os.pathconf(base, "PC_PATH_MAX")
    except (OSError, ValueError):
        name_max, path_max = 255, 4096
    if len(os.fsencode(os.path.abspath(path))) >= path_max:
        raise InputError(f"the path is {len(path)} characters long, more than the file system allows", key=flag,
                         expected=f"{what}, shorter than {path_max} bytes")
    for part in Path(path).parts:
        if len(os.fsencode(part)) > name_max:
            raise InputError(f"the name {part[:40]}... is {len(part)} characters long", key=flag,
                             expected=f"{what}, each name at most {name_max} bytes")


def check_replaceable(flag: str, target: Path, what: str) -> None:
    """Refuse an existing ``target`` that is not a regular file or a link (a device, FIFO, socket, folder):
    writing by rename would replace the node itself (as root, /dev/null), writing into it is not a file."""
    try:
        mode = os.lstat(target).st_mode
    except (FileNotFoundError, NotADirectoryError):  # a new name (a parent that is a file: refused below)
        return
    except OSError as exc:
        raise InputError(f"cannot inspect {target} ({exc.strerror})", key=flag, expected=what) from None
    if not (stat.S_ISREG(mode) or stat.S_ISLNK(mode)):
        raise InputError(f"{target} exists and is {file_kind(mode)}, not a regular file", key=flag,
                         expected=f"{what}: a new name or a regular file to replace")


def _write_json(path: str, results: dict) -> None:
    """Write the results JSON through a temporary file in the same folder (never half a file, never
    a temporary file left behind; an existing link is replaced, never followed; a target that became a device
    or FIFO since the check is refused)."""
    target = Path(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=".tmp-", suffix=".json")
    except OSError as exc:
        raise InputError(f"cannot write {path} ({exc.strerror})", key="--json",
                         expected="a path for the JSON file in a writable folder") from None
    try:
        with os.fdopen(fd, "w") as fh:
            json.dump({k: v for k, v in results.items() if not k.startswith("_")}, fh, indent=2, default=float)
        check_replaceable("--json", target, "a path for the JSON file")
        os.replace(tmp, target)
    except OSError as exc:
        raise InputError(f"cannot write {path} ({exc.strerror})", key="--json",
                         expected="a path for the JSON file in a writable folder") from None
    finally:
        if os.path.lexists(tmp):
            os.unlink(tmp)


def _cmd_run(args) -> int:
    from mechgen.scene.report import summary
    from mechgen.scene.run import check_backend, check_scheduler, run_scene

    check_backend(args.backend)
    if args.scheduler is not None:
        check_scheduler("--scheduler", args.scheduler)
    if args.json_path is not None:
        check_output("--json", args.json_path, folder=False)
    if args.plot_dir is not None:
        check_output("--plot", args.plot_dir, folder=True)
    try:
        results = run_scene(args.scene, overrides=args.overrides, backend=args.backend, scheduler=args.scheduler)
    except MechgenError as exc:  # the analyses before the failed one are printed and written, then the error
        partial = getattr(exc, "partial_results", None)
        if partial is not None:
            _report(args, partial, summary)
        raise
    _report(args, results, summary)
    if not args.plot_dir:
        print("(mechgen run SCENE --plot DIR draws the figures)")
    return 0


def _report(args, results: dict, summary) -> None:
    """Write --json and draw --plot of a (possibly partial) results dict, then print the summary and the
    files written (printing last: a reader that goes away early, ``| head``, cannot cost the files)."""
    if args.json_path:
        _write_json(args.json_path, results)
    written = []
    if args.plot_dir:
        from mechgen.scene.plots import plot_results

        written = plot_results(results, Path(args.plot_dir))
    print(summary(results))
    for path in written:
        print(f"wrote {path}")
    sys.stdout.flush()


def _cmd_models(_args) -> int:
    """One line per model a scene can name: name, origin (built-in or the entry point's distribution), summary."""
    from mechgen import models

    rows = [(name, models.resolve(name)) for name in models.names()]
    rows += sorted(models.entry_points().items())
    wide = max(len(name) for name, _ in rows)
    origin = max(len(source.origin) for _, source in rows)
    for name, source in rows:
        try:
            summary = source.load().summary()
        except InputError as exc:  # an installed package's broken model: say so, list the others
            summary = f"(does not load: {exc.paragraph()})"
        print(f"{name:{wide}s}  {source.origin:{origin}s}  {summary}")
    return 0


def _cmd_show(args) -> int:
    from mechgen.scene.show import show_model

    print(show_model(args.model))
    return 0


def _need_checkout(command: str, folders: list[Path]) -> None:
    """Refuse a command that reads the repository's own folders (scenes/, benchmarks/) where the package was
    installed from a wheel, which ships the package only."""
    missing = [f"{folder.name}/" for folder in folders if not folder.is_dir()]
    if missing:
        raise InputError(f"mechgen {command} reads {', '.join(missing)} of a source checkout, and this mechgen "
                         f"({Path(__file__).resolve().parent}) was installed without them",
                         key=command, expected="mechgen installed from a clone of the repository "
                                               "(pip install -e . in the clone)")


def _cmd_regen(args) -> int:
    from mechgen.regen import SCENES, regen

    _need_checkout("regen", [SCENES])
    stale = regen(check=args.check)
    if args.check and stale:
        print("mechgen/generated is stale: " + ", ".join(stale) + " (run `mechgen regen`)", file=sys.stderr)
        return 1
    for path in stale:
        print(f"wrote {path}")
    return 0


def _cmd_bench(args) -> int:
    from mechgen.bench import run_benchmarks, suite_lines

    if args.list_suites:
        print("\n".join(suite_lines()))
        return 0
    from mechgen.bench.common import ROOT

    _need_checkout("bench", [ROOT / "scenes", ROOT / "benchmarks"])
    run_benchmarks(args.models, out=Path(args.out), quick=args.quick)
    return 0


def _cmd_export(args) -> int:
    from mechgen.export import export_model

    for path in export_model(args.model, args.backend, Path(args.out_dir), sets=args.overrides,
                             kernels=args.kernels):
        print(f"wrote {path}")
    return 0


def _quiet_stdout() -> None:
    """Point stdout at /dev/null so that Python's flush at exit does not raise into a closed pipe again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):
        pass


COMMANDS = {"run": _cmd_run, "models": _cmd_models, "show": _cmd_show, "regen": _cmd_regen, "bench": _cmd_bench,
            "export": _cmd_export}


#: how long OpenBLAS's idle threads spin-wait for the next call before they sleep in a ``mechgen`` process: 2^20
#: cycles (about 0.4 ms) against OpenBLAS's 2^28 (about 0.1 s). At load, numpy's OpenBLAS starts its threads and
#: they spin for that long: a cached ``mechgen run scenes/laval_rotor.toml`` spent 0.36-0.48 s of CPU against
#: 0.26-0.35 s at 2^20 (as with one thread), and those spinning threads take a busy machine's cores from other
#: work. Kept as the user sets it (OPENBLAS_THREAD_TIMEOUT, 4 ... 30).
BLAS_SPIN = "20"


def console() -> int:
    """The ``mechgen`` command (and ``python -m mechgen``): :func:`main` in a process of its own, whose OpenBLAS
    threads spin for :data:`BLAS_SPIN` unless the environment says otherwise. Set before numpy loads OpenBLAS
    (mechgen.cli imports no numpy); it changes no number, only how long idle threads burn CPU."""
    if "numpy" not in sys.modules:
        os.environ.setdefault("OPENBLAS_THREAD_TIMEOUT", BLAS_SPIN)
    return main()


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``mechgen`` command (argv: its arguments; None: sys.argv's)."""
    parser = _parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    try:
        return COMMANDS[args.command](args)
    except BrokenPipeError:  # the reader went away (mechgen run ... | head): stop quietly, as Python's docs advise
        _quiet_stdout()
        return 1
    except InputError as exc:
        print(f"mechgen: {exc.paragraph()}", file=sys.stderr)
        return 2
    except MechgenError as exc:
        print(f"mechgen: {type(exc).__name__}: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
