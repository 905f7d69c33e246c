"""The `gearjax` command.

    gearjax run [SCENE.toml] [--json] [--no-cache]
    gearjax reproduce curvilinear|dca [--json] [--cross-check] [--no-cache]
    gearjax optimize [SCENE.toml] [--method ga|gradient] [--out DIR] [--resume] [--json] [--quiet]
    gearjax sweep [SCENE.toml] --torque-Nm LIST --speed-rpm LIST [--chunk N] [--out DIR] [--resume]
                  [--json] [--plot] [--quiet]

    gearjax --version

With no file it runs the built-in default scene (seed 001's 29/71 helical pair with the
paper's optimal modification). `--json` prints one JSON object (keys in the README). A bad
scene file (a field out of range, a file that cannot be read or is not UTF-8 text) prints
one line naming the field as `[section] key: ...` and exits with status 2; so does a bad
argument. `reproduce` runs the
reproductions of `gearjax.papers` (the command is presentation: it may import the papers
package, the core may not).

Programs are cached on disk (`$GEARJAX_CACHE_DIR`, default `~/.cache/gearjax/jax`): JAX's
persistent compilation cache (`gearjax.runtime.cache`) holds the compiled programs and gearjax's
program cache (`gearjax.runtime.program_cache`, in `programs/`) the traced ones, so a second run
of the same scene structure neither traces nor compiles; `--no-cache` disables both. The
program cache is enabled for the command's own call only, so calling `main` in a process
(tests, notebooks) leaves the process's setting as it was.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import re
import sys


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (`gearjax CMD: error: ...; see
    gearjax CMD --help`) and exit status 2, like the scene file's."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}; see {self.prog} --help\n")


#: Options whose value may start with "-" (a list with a negative number is a bad value,
#: which `parse_list` names; argparse would take it for an option).
_VALUE_OPTIONS = ("--torque-Nm", "--speed-rpm", "--chunk")
_NUMBER_LIKE = re.compile(r"-[\d.]")


def _attach_values(argv: list[str]) -> list[str]:
    """`--torque-Nm -5,100` as `--torque-Nm=-5,100`, so that the value reaches its check."""
    out: list[str] = []
    i = 0
    while i < len(argv):
        if argv[i] in _VALUE_OPTIONS and i + 1 < len(argv) and _NUMBER_LIKE.match(argv[i + 1]):
            out.append(f"{argv[i]}={argv[i + 1]}")
            i += 2
        else:
            out.append(argv[i])
            i += 1
    return out


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    from .. import __version__

    try:
        jax_version = version("jax")
    except PackageNotFoundError:  # pragma: no cover - jax is a dependency
        jax_version = "not installed"
    return f"gearjax {__version__} (jax {jax_version}, Python {sys.version.split()[0]})"


def _enable_x64() -> None:
    # The command is an application, so it may choose the precision; the library itself
    # never flips global JAX flags on import.
    import jax

    jax.config.update("jax_enable_x64", True)


#: The command stores even its quickest compilations: building and reporting a scene runs
#: about a hundred small eager operations, each compiled in tens of ms, which together cost
#: more than the traced program's load (the library's default skips them, see
#: `gearjax.runtime.cache.MIN_COMPILE_TIME_S`).
COMMAND_MIN_COMPILE_TIME_S = 0.0


@contextlib.contextmanager
def _caches(args: argparse.Namespace):
    """The compilation and program caches for the command's own work, unless --no-cache.

    A fresh process (the command's normal case) gets the persistent cache; when the command
    is called in a process that has already compiled programs (tests, notebooks) the
    process's cache directory stays. The program cache and the lower compile-time threshold
    apply inside the command only: on return the process's settings are as they were."""
    import jax

    from ..runtime.cache import _cache_started, enable_compilation_cache
    from ..runtime.program_cache import program_cache

    # programs are cached; with jaxlib < 0.12 `optimize`'s gradient program keeps itself
    # out (`gearjax.runtime.cache`: it could not be loaded back)
    if args.no_cache:
        # nor a cache that JAX was pointed at by its own settings ($JAX_COMPILATION_CACHE_DIR);
        # JAX decides at the process's first compilation, so a started cache stays
        enabled = jax.config.jax_enable_compilation_cache
        if not _cache_started():
            jax.config.update("jax_enable_compilation_cache", False)
        try:
            with program_cache(enabled=False):
                yield
        finally:
            jax.config.update("jax_enable_compilation_cache", enabled)
        return
    if not _cache_started():
        enable_compilation_cache(programs=False)
    option = "jax_persistent_cache_min_compile_time_secs"
    previous = getattr(jax.config, option)
    jax.config.update(option, COMMAND_MIN_COMPILE_TIME_S)
    try:
        with program_cache():
            yield
    finally:
        jax.config.update(option, previous)


def _run(args: argparse.Namespace) -> int:
    from ..io.report import result_dict, summary
    from ..pipeline import simulate
    from ..papers.seed001 import SEED_001_NOTE
    from ..io.scene_file import SceneFileError, default_scene, load_scene

    try:
        if args.scene is None:
            scene, _ = default_scene()
            notes = [SEED_001_NOTE]
        else:
            scene, _ = load_scene(args.scene)
            notes = []
    except SceneFileError as err:
        print(f"gearjax: error: {err}", file=sys.stderr)
        return 2
    if "impact" not in scene.effects and float(scene.operating.speed) > 0.0:
        notes.append(
            "[operating] speed_rpm is used by the mesh-in impact only, which this scene does not compute; "
            "add effects = [\"impact\"] to [analysis] (with a torque) to compute it")
    from ..runtime.resources import MemoryEstimateError

    # The summary reports every stage's result code, so a failed stage is shown, not raised.
    from ..io.progress import compiling

    try:
        with compiling(f"the {_program_kind(scene)} program for this scene structure"):
            result = simulate(scene, throw=False)
    except MemoryEstimateError as err:
        print(f"gearjax: error: {err}", file=sys.stderr)
        return 2
    out = result_dict(scene, result, notes)
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        print(summary(out))
    return 0


def _program_kind(scene) -> str:
    """The last stage of a scene's program, in words."""
    if "impact" in scene.effects:
        return "mesh-in impact"
    return "loaded contact" if "ltca" in scene.effects else "tooth contact"


def _reproduce(args: argparse.Namespace) -> int:
    from ..papers import curvilinear, double_arc

    if args.paper == "dca":
        out = double_arc.reproduce(cross_check=args.cross_check)
        print(json.dumps(out, indent=2) if args.json else double_arc.summary(out))
        return 0
    out = curvilinear.reproduce()
    print(json.dumps(out, indent=2) if args.json else curvilinear.summary(out))
    return 0


def _optimize(args: argparse.Namespace) -> int:
    from .optimize import run_command

    return run_command(args.scene, args.method, args.out, args.resume, args.json, args.quiet)


def _sweep(args: argparse.Namespace) -> int:
    from .sweep import run_command

    return run_command(args.scene, args.torque_Nm, args.speed_rpm, args.out, args.json, args.plot,
                       chunk=args.chunk, resume=args.resume, quiet=args.quiet)


def main(argv: list[str] | None = None) -> int:
    parser = _Parser(prog="gearjax", description="Differentiable gear contact engine.")
    parser.add_argument("--version", action="version", version=_version())
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="simulate a scene (default: the built-in seed 001 scene)")
    run.add_argument("scene", nargs="?", help="TOML scene file")
    run.add_argument("--json", action="store_true", help="print one JSON object")
    rep = sub.add_parser("reproduce", help="a paper's quantities beside gearjax's")
    rep.add_argument("paper", choices=["curvilinear", "dca"], help="curvilinear: seed 002; dca: seeds 000/003")
    rep.add_argument("--json", action="store_true", help="print one JSON object")
    rep.add_argument(
        "--cross-check", action="store_true",
        help="dca: also run the general TCA on the generated surfaces with the seed's pitch error (~2 min)",
    )
    opt = sub.add_parser("optimize", help="tune the pinion modification for a small mesh-in impact ([optimize] section)")
    opt.add_argument("scene", nargs="?", help="TOML scene file with an optional [optimize] section (default: the built-in scene)")
    opt.add_argument("--method", choices=["ga", "gradient"], help="overrides optimize.method")
    opt.add_argument("--out", default="gearjax-optimize", help="run directory (default ./gearjax-optimize)")
    opt.add_argument("--resume", action="store_true", help="continue the run in --out")
    opt.add_argument("--json", action="store_true", help="print one JSON object")
    opt.add_argument("--quiet", action="store_true", help="plain progress lines instead of a progress bar")
    swp = sub.add_parser("sweep", help="mesh-in impact over a torque x speed grid, in one compiled call")
    swp.add_argument("scene", nargs="?", help="TOML scene file with effects = [\"impact\"] (default: the built-in scene)")
    swp.add_argument("--torque-Nm", required=True, dest="torque_Nm",
                     help="pinion torques (N m): 100,400,1000 or start:stop:count")
    swp.add_argument("--speed-rpm", required=True, dest="speed_rpm",
                     help="pinion speeds (rpm): 1000,5000 or start:stop:count")
    swp.add_argument("--chunk", type=int, help="torques per chunk (default: all at once); each chunk is written when done")
    swp.add_argument("--out", help="run directory: each finished chunk, then sweep.json and sweep.npz (and the plots)")
    swp.add_argument("--resume", action="store_true", help="continue the killed or finished run in --out")
    swp.add_argument("--json", action="store_true", help="print one JSON object")
    swp.add_argument("--plot", action="store_true", help="also write sweep_force_map.png and sweep_harris.png (needs --out)")
    swp.add_argument("--quiet", action="store_true", help="plain progress lines instead of a progress bar")
    for command in (run, rep, opt, swp):
        command.add_argument(
            "--no-cache", action="store_true",
            help="do not use the compilation and program caches ($GEARJAX_CACHE_DIR, default ~/.cache/gearjax/jax)",
        )
    args = parser.parse_args(_attach_values(sys.argv[1:] if argv is None else list(argv)))
    _enable_x64()
    with _caches(args):
        if args.command == "run":
            return _run(args)
        if args.command == "optimize":
            return _optimize(args)
        if args.command == "sweep":
            return _sweep(args)
        return _reproduce(args)
