"""gearjax's program cache: `simulate`'s traced program, exported to disk with `jax.export`.

Tracing `simulate` (Python builds the jaxpr: about 12 s for the default scene) and
lowering it (about 2 s) happen in every process, even when JAX's persistent compilation
cache (`gearjax.runtime.cache`) holds the compiled program. This cache stores the lowered program
(`jax.export.Exported.serialize()`: the StableHLO bytecode and its calling convention)
with the structure of its result, so a later process neither traces nor lowers
`simulate`: it loads the program, calls it (its compilation is then found in JAX's cache)
and rebuilds the `SimulationResult`. Cold or warm, the exported program is what runs, so
both give the same numbers; `simulate(throw=...)` checks them afterwards as ever.

What is keyed: an entry's key is a SHA-256 of everything the program depends on: the
scene's pytree structure with every static field (`Accuracy`, effects, tooth counts, ...),
its arrays' shapes and dtypes, the contents of gearjax's source files, the versions of
Python, JAX, jaxlib, equinox, optimistix, lineax and numpy, the backend and device kind,
the JAX settings that change tracing (`jax_enable_x64`, dtype/rank promotion, default
matmul precision) and the entry format. A changed source file or another scene structure
is a new key, never a stale program. A class of the scene defined outside these packages
keys by its module file's contents. The cached function itself is named by its qualified
name (it is gearjax's, so the source digest covers its code).

What bypasses it: a scene class with no source file (a notebook cell, `python -c`) or a
static value that cannot be keyed (a lambda, an arbitrary object); a call that is not a
top-level call on concrete arrays (under `jit`, `vmap` or `grad` the scene's leaves are
tracers), or with `jax_disable_jit`, `jax_debug_nans`/`jax_debug_infs`; a program that
cannot be exported or serialized. Such a call traces as without the cache.
`program_cache_info()` counts hits, loads, misses, writes and bypasses in this process,
and logger `gearjax.runtime.program_cache` says (at INFO) what was loaded or stored.

What the key cannot see: code outside gearjax that tracing runs but that is not the module
of a class in the scene (a helper module that a user's family imports), and functions
monkeypatched at run time. Disable the program cache while editing such code.

Where it is stored: `enable_compilation_cache()` (see `gearjax.runtime.cache`) enables it in the
subdirectory `programs/` of the cache directory; `enable_program_cache()` /
`disable_program_cache()` switch it alone, and `with program_cache(): ...` enables it for
a block only (the command line's way). One file per scene structure,
`<name>-<key prefix>.gjprog` (about 1 MB for the default scene), written atomically (a
temporary file, then `os.replace`). The file is a pickle of `{"format", "key", "exported"
(the serialized `Exported`), "structure"}`; an entry of another format, another key, or one
that fails to load or run is a miss (and is replaced), never an error. Like JAX's cache,
the program cache loads what it finds there (the entries are pickles), so the directory
must be writable only by its user. A program used once in the process is also kept in
memory, so later calls with the same key neither read the file nor compile again.
"""

from __future__ import annotations

import contextlib
import logging
import os
import pickle
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import jax

from .program_key import Uncacheable, program_key
from .directories import default_cache_dir, make_cache_dir

#: Subdirectory of the cache directory that holds the program cache's entries.
PROGRAMS_SUBDIR = "programs"
#: Version of the entry format (part of the key); bumping it orphans old entries.
#: 1: private fields of `jax.export.Exported`; 2: `Exported.serialize()`.
FORMAT = 2
_SUFFIX = ".gjprog"

logger = logging.getLogger(__name__)

_program_dir: Path | None = None
_info = {"hits": 0, "loads": 0, "misses": 0, "writes": 0, "bypassed": 0}
#: Programs used in this process, by (entry path, key): (jitted call, result structure).
_programs: dict[tuple[Path, str], tuple[Callable, Any]] = {}


# --------------------------------------------------------------------------------------
# Switches


def enable_program_cache(path: str | os.PathLike | None = None) -> Path:
    """Store traced programs of `simulate` in `path` (default
    `default_cache_dir() / "programs"`) and load them from there. Unlike JAX's
    compilation cache it can be switched at any time.

    Returns:
        the directory (created if missing).
    """
    global _program_dir
    directory = Path(path).expanduser() if path is not None else default_cache_dir() / PROGRAMS_SUBDIR
    _program_dir = make_cache_dir(directory)
    return _program_dir


def disable_program_cache() -> None:
    """Stop using the program cache (its files stay)."""
    global _program_dir
    _program_dir = None


def program_cache_dir() -> Path | None:
    """The program cache's directory, or None when it is off."""
    return _program_dir


@contextlib.contextmanager
def program_cache(enabled: bool = True, path: str | os.PathLike | None = None) -> Iterator[Path | None]:
    """Enable (or, with `enabled=False`, disable) the program cache inside the block only;
    the previous setting returns on exit. Yields the directory in use (None when off)."""
    global _program_dir
    previous = _program_dir
    try:
        if enabled:
            enable_program_cache(path)
        else:
            disable_program_cache()
        yield _program_dir
    finally:
        _program_dir = previous


def program_cache_info() -> dict[str, int]:
    """Counts of this process: `hits` (calls that ran a cached program, read from disk or
    kept from an earlier call), `loads` (entries read from disk), `misses` (programs traced
    and exported), `writes` (entries stored), `bypassed` (calls that could not use the
    cache: traced arguments, a scene that cannot be keyed, a failed export)."""
    return dict(_info)


# --------------------------------------------------------------------------------------
# The call


class _Slot:
    """Stands for the `index`-th array output in an entry's stored result structure."""

    __slots__ = ("index",)

    def __init__(self, index: int):
        self.index = index

    def __reduce__(self):
        return (_Slot, (self.index,))


class _ExportFailed(Exception):
    """The traced program could not be exported or serialized."""


def cached_call(fn: Callable[[Any], Any], tree: Any, *, name: str) -> Any:
    """`fn(tree)` through the program cache when it is enabled, else `fn(tree)`.

    `fn` is a function of one pytree with `equinox.filter_jit` semantics: the array leaves
    of `tree` are the program's inputs, every other leaf and the pytree structure are
    baked into it. On a miss the program is traced and exported (`jax.export`) and the
    entry stored; hit or miss, the exported program is what runs. Output leaves that are
    not arrays are stored with the result structure.

    Args:
        fn: the (jit-able) function.
        tree: its argument.
        name: the entry's name (file prefix and part of the key).

    Returns:
        `fn(tree)`.
    """
    import equinox as eqx

    directory = _program_dir
    if directory is None:
        return fn(tree)
    leaves, treedef = jax.tree_util.tree_flatten(tree)
    try:
        key = _entry_key(fn, name, treedef, leaves)
    except Uncacheable as err:
        _info["bypassed"] += 1
        logger.debug("program cache: %s bypassed (%s)", name, err)
        return fn(tree)
    path = directory / f"{name}-{key[:40]}{_SUFFIX}"
    arrays = [leaf for leaf in leaves if eqx.is_array(leaf)]
    program = _programs.get((path, key)) or _load(path, key)
    if program is not None:
        try:
            outputs = program[0](*arrays)
        except Exception as err:  # noqa: BLE001 - a broken entry must not break the call
            logger.warning("program cache: stored program %s failed (%s: %s); tracing instead",
                           path.name, type(err).__name__, err)
            _programs.pop((path, key), None)
            _remove(path)
            return fn(tree)
        _info["hits"] += 1
    else:
        program = _trace_and_store(fn, treedef, leaves, path, key)
        if program is None:
            return fn(tree)
        outputs = program[0](*arrays)
    _programs[(path, key)] = program
    return _rebuild(program[1], outputs)


def _entry_key(fn, name: str, treedef, leaves: list) -> str:
    """The call's key; raises `Uncacheable` when the call must bypass the cache."""
    if any(isinstance(leaf, jax.core.Tracer) for leaf in leaves):
        raise Uncacheable("called inside a transformation")
    for flag in ("jax_disable_jit", "jax_debug_nans", "jax_debug_infs"):
        if getattr(jax.config, flag, False):
            raise Uncacheable(flag)
    for leaf in leaves:
        dtype = getattr(leaf, "dtype", None)
        if dtype is not None and jax.dtypes.issubdtype(dtype, jax.dtypes.extended):
            raise Uncacheable(f"extended dtype {dtype}")
    return program_key(fn, name, treedef, leaves, FORMAT)


def _trace_and_store(fn, treedef, leaves, path: Path, key: str):
    """A miss: export `fn`, store the entry; its (jitted call, result structure), or None
    (counted as bypassed) when the program cannot be exported."""
    start = time.perf_counter()
    try:
        exported, serialized, structure = _export(fn, treedef, leaves)
    except _ExportFailed as err:
        _info["bypassed"] += 1
        logger.warning("program cache: %s could not be exported (%s); running it uncached", path.name, err)
        return None
    _info["misses"] += 1
    logger.info("program cache: traced and exported %s in %.1f s", path.name, time.perf_counter() - start)
    _store(path, key, serialized, structure)
    return jax.jit(exported.call), structure


def _export(fn, treedef, leaves):
    """Trace, lower, export and serialize `fn` as a function of the tree's array leaves
    (flat), with the structure of its result with `_Slot`s where its arrays go."""
    import equinox as eqx
    from jax import export

    is_array = [eqx.is_array(leaf) for leaf in leaves]
    specs = []
    for leaf, array in zip(leaves, is_array, strict=True):
        if array:
            aval = jax.typeof(leaf)
            specs.append(jax.ShapeDtypeStruct(aval.shape, aval.dtype, weak_type=aval.weak_type))
    structures = []

    def flat_fn(*arrays):
        it = iter(arrays)
        tree = treedef.unflatten([next(it) if array else leaf for leaf, array in zip(leaves, is_array, strict=True)])
        out_leaves, out_treedef = jax.tree_util.tree_flatten(fn(tree))
        slots, outputs = [], []
        for leaf in out_leaves:
            if eqx.is_array(leaf):
                slots.append(_Slot(len(outputs)))
                outputs.append(leaf)
            else:
                slots.append(leaf)
        structures.append(out_treedef.unflatten(slots))
        return outputs

    flat_fn.__name__ = flat_fn.__qualname__ = getattr(fn, "__name__", "program")
    try:
        exported = export.export(jax.jit(flat_fn))(*specs)
        serialized = bytes(exported.serialize())
    except Exception as err:
        if not structures:
            raise  # the function itself failed to trace: the user's error, not the cache's
        raise _ExportFailed(f"{type(err).__name__}: {err}") from err
    return exported, serialized, structures[0]


def _rebuild(structure, outputs):
    leaves, treedef = jax.tree_util.tree_flatten(structure)
    return treedef.unflatten([outputs[leaf.index] if isinstance(leaf, _Slot) else leaf for leaf in leaves])


# --------------------------------------------------------------------------------------
# Entries on disk


def _store(path: Path, key: str, serialized: bytes, structure) -> None:
    start = time.perf_counter()
    try:
        blob = pickle.dumps(
            {"format": FORMAT, "key": key, "exported": serialized, "structure": structure},
            protocol=pickle.HIGHEST_PROTOCOL,
        )
    except Exception as err:  # noqa: BLE001 - an unpicklable result only costs the entry
        logger.warning("program cache: %s not stored (%s: %s)", path.name, type(err).__name__, err)
        return
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        handle, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=_SUFFIX)
        try:
            with os.fdopen(handle, "wb") as file:
                file.write(blob)
            os.replace(tmp, path)
        except BaseException:
            _remove(Path(tmp))
            raise
    except OSError as err:
        logger.warning("program cache: %s not stored (%s)", path, err.strerror or err)
        return
    _info["writes"] += 1
    logger.info("program cache: stored %s (%.1f MB) in %.2f s", path, len(blob) / 1e6, time.perf_counter() - start)


def _load(path: Path, key: str):
    """The entry's (jitted call, result structure), or None when missing or unusable (of
    another format or key, corrupt, or not deserializable by this JAX)."""
    try:
        blob = path.read_bytes()
    except FileNotFoundError:
        return None
    except OSError as err:
        logger.warning("program cache: %s unreadable (%s)", path, err.strerror or err)
        return None
    from jax import export

    start = time.perf_counter()
    try:
        entry = pickle.loads(blob)
        if not isinstance(entry, dict) or entry.get("format") != FORMAT or entry.get("key") != key:
            raise ValueError("key or format mismatch")
        exported = export.deserialize(bytearray(entry["exported"]))
        structure = entry["structure"]
        slots = [leaf for leaf in jax.tree_util.tree_leaves(structure) if isinstance(leaf, _Slot)]
        if sorted(slot.index for slot in slots) != list(range(len(exported.out_avals))):
            raise ValueError("the result structure does not match the program's outputs")
    except Exception as err:  # noqa: BLE001 - a corrupt or old entry is a miss, and is replaced
        logger.warning("program cache: ignoring %s (%s: %s)", path.name, type(err).__name__, err)
        return None
    _info["loads"] += 1
    logger.info("program cache: loaded %s in %.2f s", path, time.perf_counter() - start)
    return jax.jit(exported.call), structure


def _remove(path: Path) -> None:
    with contextlib.suppress(OSError):
        path.unlink()
