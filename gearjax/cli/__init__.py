"""The `gearjax` command.

    gearjax run [SCENE.toml] [--json] [--no-cache]
    gearjax reproduce seed001|curvilinear|dca [--json] [--cross-check] [--accuracy SPEC] [--check-slices N]
                      [--no-cache]
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
#: dozens of small eager operations, which together compile in over a second (the
#: library's default skips them, see `gearjax.runtime.cache.MIN_COMPILE_TIME_S`).
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


#: The sub-commands, each a module of this package with `HELP`, `add_arguments(parser)` and
#: `run(args) -> exit status`; a new command is a module and a name here.
COMMANDS = ("run", "reproduce", "optimize", "sweep")


def build_parser() -> tuple[argparse.ArgumentParser, dict]:
    """The `gearjax` parser with its sub-commands, and the commands' modules by name (the
    documentation's CLI reference is generated from it)."""
    import importlib

    parser = _Parser(prog="gearjax", description="Differentiable gear contact engine.")
    parser.add_argument("--version", action="version", version=_version())
    sub = parser.add_subparsers(dest="command", required=True)
    modules = {name: importlib.import_module(f".{name}", __name__) for name in COMMANDS}
    for name, module in modules.items():
        command = sub.add_parser(name, help=module.HELP, description=module.HELP)
        module.add_arguments(command)
        command.add_argument(
            "--no-cache", action="store_true",
            help="do not use the compilation and program caches ($GEARJAX_CACHE_DIR, default ~/.cache/gearjax/jax)",
        )
    return parser, modules


def main(argv: list[str] | None = None) -> int:
    parser, modules = build_parser()
    args = parser.parse_args(_attach_values(sys.argv[1:] if argv is None else list(argv)))
    _enable_x64()
    with _caches(args):
        return modules[args.command].run(args)
