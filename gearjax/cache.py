"""Caches that let a later process skip the work of an earlier one.

Running a scene costs, before any number is computed, tracing `simulate`'s program (Python
builds the jaxpr: about 12 s for the default scene), lowering it to StableHLO (about 2 s)
and compiling it with XLA (about a minute on a 2-core CPU). Two caches on disk remove that:

* **JAX's persistent compilation cache** (`jax_compilation_cache_dir`) stores compiled XLA
  executables, keyed by the lowered program, the JAX version and the backend. It never
  stores a program that contains a host callback, which is why gearjax's programs report
  solver failures as result codes (`gearjax.RESULTS`) instead of runtime checks.
* **gearjax's program cache** stores the traced and lowered program of `simulate`
  (`jax.export.Exported.serialize()`: the StableHLO bytecode and its calling convention)
  with the structure of its result, so a later process neither traces nor lowers
  `simulate`: it loads the program, calls it (its compilation is then found in JAX's
  cache) and rebuilds the `SimulationResult`. Cold or warm, the exported program is what runs, so both give the
  same numbers; `simulate(throw=...)` checks them afterwards as ever. An entry is keyed by a
  SHA-256 of everything the program depends on: the scene's pytree structure with every
  static field (`Accuracy`, effects, tooth counts, ...), its arrays' shapes and dtypes, the
  contents of gearjax's source files, the versions of Python, JAX, jaxlib, equinox,
  optimistix, lineax and numpy, the backend and device kind, and the JAX settings that
  change tracing (`jax_enable_x64`, dtype/rank promotion, default matmul precision). A
  changed source file or another scene structure is a new key, never a stale program. A
  class of the scene defined outside these packages keys by its module file's contents; one
  with no file (a notebook cell, `python -c`) or a static value that cannot be keyed (a
  lambda, an arbitrary object) bypasses the cache.

The command line enables both by default, and while it runs it stores even its quickest
compilations (the scene's checks and the report run about a hundred small eager programs;
`gearjax ... --no-cache` disables all of it). The library never changes JAX's
configuration on import, so in Python the caches are opt-in:

    import gearjax as gj
    gj.enable_compilation_cache()          # before the first computation; both caches
    gj.enable_compilation_cache(programs=False)   # JAX's cache only

`enable_program_cache()` / `disable_program_cache()` switch the program cache alone, and
`with program_cache(): ...` enables it for a block only (the command line's way).

The program cache applies only to a top-level call of `simulate` on concrete arrays: under
`jit`, `vmap` or `grad` (the scene's leaves are tracers), with `jax_disable_jit`, or with
`jax_debug_nans`/`jax_debug_infs`, `simulate` traces as without it. `program_cache_info()`
counts its hits, misses, writes and bypasses in this process, and logger
`gearjax.cache` says (at INFO) what was loaded or stored.

What the key cannot see: code outside gearjax that tracing runs but that is not the module
of a class in the scene (a helper module that a user's family imports), and functions
monkeypatched at run time. Disable the program cache while editing such code.

On a 2-core CPU shared with other jobs (load 4-7; rough), a warm `gearjax run` of the
default scene took 8-16 s instead of 31-57 s without the program cache; what remains is
mostly loading the compiled executable from JAX's cache (2-7 s: the default scene's
executable is 22 MB), importing JAX/equinox/optimistix (about 2.5 s), building and
checking the scene (about 2 s of small eager programs) and lowering the loaded program's
call (about 1.5 s).

The cache directory is `$GEARJAX_CACHE_DIR` if set, else `$XDG_CACHE_HOME/gearjax/jax`
(`~/.cache/gearjax/jax`); the program cache uses its subdirectory `programs/` (one file
per scene structure, about 1 MB for the default scene, written atomically: a temporary
file, then `os.replace`); an entry of another format or key, or one that fails to load, is
a miss (and is replaced), never an error. Delete the directory to reclaim space.
Like JAX's cache, the program cache loads what it finds there (the entries are pickles), so
the directory must be writable only by its user.
"""

from __future__ import annotations

import contextlib
import dataclasses
import enum
import functools
import hashlib
import logging
import os
import pickle
import sys
import tempfile
import time
import types
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import jax

#: Environment variable that moves the cache directory.
ENV_VAR = "GEARJAX_CACHE_DIR"
#: Programs that compile faster than this (s) are not written: small eager operations
#: would otherwise fill the directory with entries that save nothing.
MIN_COMPILE_TIME_S = 0.2
#: Subdirectory of the cache directory that holds the program cache's entries.
PROGRAMS_SUBDIR = "programs"
#: Version of the program cache's entry format and key; bumping it orphans old entries.
#: 1: private fields of `jax.export.Exported`; 2: `Exported.serialize()`.
_FORMAT = 2
_SUFFIX = ".gjprog"

logger = logging.getLogger(__name__)

_program_dir: Path | None = None
_info = {"hits": 0, "loads": 0, "misses": 0, "writes": 0, "bypassed": 0}


def default_cache_dir() -> Path:
    """`$GEARJAX_CACHE_DIR`, else `$XDG_CACHE_HOME/gearjax/jax` (default `~/.cache`)."""
    path = os.environ.get(ENV_VAR)
    if path:
        return Path(path).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base).expanduser() / "gearjax" / "jax"


def _make_dir(directory: Path) -> Path:
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ValueError(f"cache directory {str(directory)!r} cannot be created ({err.strerror}); "
                         f"set {ENV_VAR} to a writable directory") from None
    return directory


def enable_compilation_cache(path: str | os.PathLike | None = None, *, programs: bool = True) -> Path:
    """Store compiled programs in `path` (default `default_cache_dir()`) and load them from
    there in later processes. Call it before the first computation of the process.

    Args:
        path: the cache directory.
        programs: also enable the program cache (traced programs of `simulate`, in
            `path/programs`), so that a later process skips tracing as well.

    Returns:
        the cache directory (created if missing).
    """
    directory = _make_dir(Path(path).expanduser() if path is not None else default_cache_dir())
    if _cache_started() and jax.config.jax_compilation_cache_dir != str(directory):
        warnings.warn(
            "JAX has already compiled programs in this process with another compilation cache "
            "setting, so the cache may not take effect: call enable_compilation_cache() before "
            "the first computation",
            RuntimeWarning,
            stacklevel=2,
        )
    jax.config.update("jax_compilation_cache_dir", str(directory))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", MIN_COMPILE_TIME_S)
    if programs:
        enable_program_cache(directory / PROGRAMS_SUBDIR)
    return directory


def _cache_started() -> bool:
    """Whether JAX has already set up its persistent cache in this process (at the first
    compilation that consulted it); a directory set later is not used."""
    try:
        from jax._src import compilation_cache
    except ImportError:  # pragma: no cover - private module moved
        return False
    return bool(getattr(compilation_cache, "_cache_initialized", False))


# --------------------------------------------------------------------------------------
# Program cache: switches


def enable_program_cache(path: str | os.PathLike | None = None) -> Path:
    """Store traced programs of `simulate` in `path` (default
    `default_cache_dir() / "programs"`) and load them from there. Unlike JAX's
    compilation cache it can be switched at any time.

    Returns:
        the directory (created if missing).
    """
    global _program_dir
    directory = Path(path).expanduser() if path is not None else default_cache_dir() / PROGRAMS_SUBDIR
    _program_dir = _make_dir(directory)
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
# Program cache: the call


class _Slot:
    """Stands for the `index`-th array output in an entry's stored result structure."""

    __slots__ = ("index",)

    def __init__(self, index: int):
        self.index = index

    def __reduce__(self):
        return (_Slot, (self.index,))


class _Uncacheable(Exception):
    """The call cannot be keyed (a static value or class whose identity is unknown)."""


def cached_call(fn: Callable[[Any], Any], tree: Any, *, name: str) -> Any:
    """`fn(tree)` through the program cache when it is enabled, else `fn(tree)`.

    `fn` is a function of one pytree with `equinox.filter_jit` semantics: the array leaves
    of `tree` are the program's inputs, every other leaf and the pytree structure are
    baked into it. On a miss the program is traced and exported (`jax.export`) and the
    entry stored; hit or miss, the exported program is what runs, so a warm and a cold
    process give identical results. Output leaves that are not arrays are stored with the
    result structure. A program used once in the process is kept in memory, so later
    calls with the same key neither read the file nor compile again.

    Args:
        fn: the (jit-able) function.
        tree: its argument.
        name: the entry's name (file prefix and part of the key).

    Returns:
        `fn(tree)`.
    """
    directory = _program_dir
    if directory is None:
        return fn(tree)
    leaves, treedef = jax.tree_util.tree_flatten(tree)
    reason = _bypass_reason(leaves)
    if reason is None:
        try:
            key = _key(fn, name, treedef, leaves)
        except _Uncacheable as err:
            reason = str(err)
    if reason is not None:
        _info["bypassed"] += 1
        logger.debug("program cache: %s bypassed (%s)", name, reason)
        return fn(tree)

    import equinox as eqx

    arrays = [leaf for leaf in leaves if eqx.is_array(leaf)]
    path = directory / f"{name}-{key[:40]}{_SUFFIX}"
    program = _programs.get((path, key))
    if program is None:
        program = _load(path, key)
        if program is not None:
            _info["loads"] += 1
    if program is not None:
        call, structure = program
        try:
            outputs = call(*arrays)
        except Exception as err:  # noqa: BLE001 - a broken entry must not break the call
            logger.warning("program cache: stored program %s failed (%s: %s); tracing instead",
                           path.name, type(err).__name__, err)
            _programs.pop((path, key), None)
            _remove(path)
            return fn(tree)
        _programs[(path, key)] = program
        _info["hits"] += 1
        return _rebuild(structure, outputs)

    start = time.perf_counter()
    try:
        exported, serialized, structure = _export(fn, treedef, leaves)
    except _ExportFailed as err:
        _info["bypassed"] += 1
        logger.warning("program cache: %s could not be exported (%s); running it uncached", name, err)
        return fn(tree)
    _info["misses"] += 1
    logger.info("program cache: traced and exported %s in %.1f s", name, time.perf_counter() - start)
    _store(path, key, serialized, structure)
    program = (jax.jit(exported.call), structure)
    outputs = program[0](*arrays)
    _programs[(path, key)] = program
    return _rebuild(structure, outputs)


#: Programs used in this process, by (entry path, key): (jitted call, result structure).
_programs: dict[tuple[Path, str], tuple[Callable, Any]] = {}


def _bypass_reason(leaves: list) -> str | None:
    if any(isinstance(leaf, jax.core.Tracer) for leaf in leaves):
        return "called inside a transformation"
    for flag in ("jax_disable_jit", "jax_debug_nans", "jax_debug_infs"):
        if getattr(jax.config, flag, False):
            return flag
    for leaf in leaves:
        dtype = getattr(leaf, "dtype", None)
        if dtype is not None and jax.dtypes.issubdtype(dtype, jax.dtypes.extended):
            return f"extended dtype {dtype}"
    return None


class _ExportFailed(Exception):
    pass


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


def _store(path: Path, key: str, serialized: bytes, structure) -> None:
    start = time.perf_counter()
    try:
        blob = pickle.dumps(
            {"format": _FORMAT, "key": key, "exported": serialized, "structure": structure},
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
        if not isinstance(entry, dict) or entry.get("format") != _FORMAT or entry.get("key") != key:
            raise ValueError("key or format mismatch")
        exported = export.deserialize(bytearray(entry["exported"]))
        structure = entry["structure"]
        slots = [leaf for leaf in jax.tree_util.tree_leaves(structure) if isinstance(leaf, _Slot)]
        if sorted(slot.index for slot in slots) != list(range(len(exported.out_avals))):
            raise ValueError("the result structure does not match the program's outputs")
    except Exception as err:  # noqa: BLE001 - a corrupt or old entry is a miss, and is replaced
        logger.warning("program cache: ignoring %s (%s: %s)", path.name, type(err).__name__, err)
        return None
    logger.info("program cache: loaded %s in %.2f s", path, time.perf_counter() - start)
    return jax.jit(exported.call), structure


def _remove(path: Path) -> None:
    with contextlib.suppress(OSError):
        path.unlink()


# --------------------------------------------------------------------------------------
# Program cache: the key

#: Packages whose code is identified by their version (or, for gearjax, its sources).
_VERSIONED = ("builtins", "gearjax", "jax", "jaxlib", "equinox", "optimistix", "lineax", "numpy", "collections")
#: JAX settings that change what tracing produces.
_CONFIG = (
    "jax_enable_x64",
    "jax_numpy_dtype_promotion",
    "jax_numpy_rank_promotion",
    "jax_default_matmul_precision",
    "jax_default_prng_impl",
)


def _key(fn, name: str, treedef, leaves) -> str:
    import equinox as eqx

    parts = (
        ("format", _FORMAT),
        ("function", name, _qualified(fn)),
        ("environment", _environment()),
        ("config", tuple((flag, repr(getattr(jax.config, flag, None))) for flag in _CONFIG)),
        ("structure", _canon_treedef(treedef)),
        ("leaves", tuple(_canon_leaf(leaf, eqx.is_array(leaf)) for leaf in leaves)),
    )
    return hashlib.sha256(repr(parts).encode()).hexdigest()


def _qualified(obj) -> str:
    return f"{getattr(obj, '__module__', '?')}.{getattr(obj, '__qualname__', type(obj).__qualname__)}"


@functools.lru_cache(maxsize=1)
def _environment() -> tuple:
    """Versions, gearjax's source digest and the backend: fixed for the process."""
    import jaxlib

    versions = [("python", sys.version_info[:3]), ("jax", jax.__version__), ("jaxlib", jaxlib.__version__)]
    for module in ("equinox", "optimistix", "lineax", "numpy"):
        versions.append((module, getattr(sys.modules.get(module), "__version__", None)))
    gearjax = sys.modules.get("gearjax")
    versions.append(("gearjax", getattr(gearjax, "__version__", None)))
    device = jax.devices()[0]
    return (tuple(versions), ("sources", _package_digest()),
            ("backend", jax.default_backend(), device.platform, device.device_kind))


@functools.lru_cache(maxsize=1)
def _package_digest() -> str:
    """SHA-256 of gearjax's Python source files (names and contents)."""
    root = Path(__file__).resolve().parent
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0")
        digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()


@functools.cache
def _file_digest(filename: str) -> str:
    return hashlib.sha256(Path(filename).read_bytes()).hexdigest()


def _canon_type(cls: type) -> tuple:
    """A class's identity: its qualified name, and for a class outside the versioned
    packages its module file's contents."""
    module = getattr(cls, "__module__", None) or ""
    qualname = getattr(cls, "__qualname__", "")
    if "<" in qualname:
        raise _Uncacheable(f"class {qualname} is local")
    if module.partition(".")[0] in _VERSIONED:
        return ("type", module, qualname)
    filename = getattr(sys.modules.get(module), "__file__", None)
    if not filename:
        raise _Uncacheable(f"class {module}.{qualname} has no source file")
    try:
        return ("type", module, qualname, _file_digest(filename))
    except OSError:
        raise _Uncacheable(f"source of {module}.{qualname} unreadable") from None


def _canon_treedef(treedef) -> tuple:
    node = treedef.node_data()
    if node is None:
        return ("leaf",)
    cls, aux = node
    return (_canon_type(cls), _canon(aux), tuple(_canon_treedef(child) for child in treedef.children()))


def _canon_leaf(leaf, is_array: bool) -> tuple:
    if is_array:
        aval = jax.typeof(leaf)
        return ("array", tuple(aval.shape), str(aval.dtype), bool(aval.weak_type))
    return ("static", _canon(leaf))


def _canon(value: Any) -> Any:
    """A deterministic description (nested tuples of strings) of a static value: equal for
    values that trace the same program. Raises `_Uncacheable` for what it cannot vouch for."""
    import numpy as np

    if value is None or type(value) in (bool, int, str, bytes):
        return (type(value).__name__, repr(value))
    if isinstance(value, enum.Enum):
        return (_canon_type(type(value)), value.name)
    if isinstance(value, (bool, int, str, bytes)):
        return (_canon_type(type(value)), repr(value))
    if isinstance(value, float):
        return (_canon_type(type(value)), float(value).hex())
    if isinstance(value, complex):
        return (_canon_type(type(value)), value.real.hex(), value.imag.hex())
    if isinstance(value, (np.ndarray, np.generic)):
        array = np.asarray(value)
        return ("ndarray", str(array.dtype), array.shape, hashlib.sha256(array.tobytes()).hexdigest())
    if isinstance(value, (tuple, list)):
        return (_canon_type(type(value)), tuple(_canon(item) for item in value))
    if isinstance(value, (frozenset, set)):
        return (_canon_type(type(value)), tuple(sorted((_canon(item) for item in value), key=repr)))
    if isinstance(value, dict):
        items = sorted(((_canon(k), _canon(v)) for k, v in value.items()), key=repr)
        return (_canon_type(type(value)), tuple(items))
    if isinstance(value, type):
        return _canon_type(value)
    if dataclasses.is_dataclass(value):  # includes equinox Modules (e.g. Accuracy)
        fields = tuple(
            (field.name, _canon(getattr(value, field.name, _MISSING))) for field in dataclasses.fields(value)
        )
        return (_canon_type(type(value)), fields)
    if isinstance(value, functools.partial):
        return ("partial", _canon(value.func), _canon(value.args), _canon(value.keywords))
    if isinstance(value, (types.FunctionType, types.BuiltinFunctionType, types.MethodType)):
        if isinstance(value, types.MethodType):
            return ("method", _canon(value.__self__), value.__func__.__qualname__)
        return ("function", _canon_type(value))
    if value is _MISSING or (type(value).__qualname__ == "_Missing" and type(value).__module__.startswith("equinox")):
        return ("missing",)  # an unset field, or equinox's "no wrapper fields" marker
    raise _Uncacheable(f"static value of type {type(value).__qualname__} cannot be keyed")


_MISSING = object()
