"""The program cache's key (`gearjax.runtime.program_cache`): a SHA-256 of what a traced program
depends on, computed without tracing.

The key covers the call's function (by qualified name: it is gearjax's, whose sources are
digested), the entry format, the environment (versions of Python, JAX, jaxlib, equinox,
optimistix, lineax, numpy and gearjax, a digest of gearjax's source files, the backend and
device kind), the JAX settings that change tracing, the argument's pytree structure with
every static value (`canon`), and its arrays' shapes, dtypes and weak types (not their
values). A class outside the versioned packages is identified by its module file's
contents. What cannot be vouched for (a local class, a class with no source file, a lambda,
an arbitrary object) raises `Uncacheable`, and the call bypasses the cache.
"""

from __future__ import annotations

import dataclasses
import enum
import functools
import hashlib
import sys
import types
from pathlib import Path
from typing import Any

import jax

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


class Uncacheable(Exception):
    """The call cannot be keyed (a static value or class whose identity is unknown)."""


def program_key(fn, name: str, treedef, leaves: list, entry_format: int) -> str:
    """The key of `fn` called on the pytree `treedef.unflatten(leaves)`, as a hex digest."""
    import equinox as eqx

    parts = (
        ("format", entry_format),
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
        raise Uncacheable(f"class {qualname} is local")
    if module.partition(".")[0] in _VERSIONED:
        return ("type", module, qualname)
    filename = getattr(sys.modules.get(module), "__file__", None)
    if not filename:
        raise Uncacheable(f"class {module}.{qualname} has no source file")
    try:
        return ("type", module, qualname, _file_digest(filename))
    except OSError:
        raise Uncacheable(f"source of {module}.{qualname} unreadable") from None


def _canon_treedef(treedef) -> tuple:
    node = treedef.node_data()
    if node is None:
        return ("leaf",)
    cls, aux = node
    return (_canon_type(cls), canon(aux), tuple(_canon_treedef(child) for child in treedef.children()))


def _canon_leaf(leaf, is_array: bool) -> tuple:
    if is_array:
        aval = jax.typeof(leaf)
        return ("array", tuple(aval.shape), str(aval.dtype), bool(aval.weak_type))
    return ("static", canon(leaf))


def canon(value: Any) -> Any:
    """A deterministic description (nested tuples of strings) of a static value: equal for
    values that trace the same program. Raises `Uncacheable` for what it cannot vouch for."""
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
        return (_canon_type(type(value)), tuple(canon(item) for item in value))
    if isinstance(value, (frozenset, set)):
        return (_canon_type(type(value)), tuple(sorted((canon(item) for item in value), key=repr)))
    if isinstance(value, dict):
        items = sorted(((canon(k), canon(v)) for k, v in value.items()), key=repr)
        return (_canon_type(type(value)), tuple(items))
    if isinstance(value, type):
        return _canon_type(value)
    if dataclasses.is_dataclass(value):  # includes equinox Modules (e.g. Accuracy)
        fields = tuple(
            (field.name, canon(getattr(value, field.name, _MISSING))) for field in dataclasses.fields(value)
        )
        return (_canon_type(type(value)), fields)
    if isinstance(value, functools.partial):
        return ("partial", canon(value.func), canon(value.args), canon(value.keywords))
    if isinstance(value, (types.FunctionType, types.BuiltinFunctionType, types.MethodType)):
        if isinstance(value, types.MethodType):
            return ("method", canon(value.__self__), value.__func__.__qualname__)
        return ("function", _canon_type(value))
    if value is _MISSING or (type(value).__qualname__ == "_Missing" and type(value).__module__.startswith("equinox")):
        return ("missing",)  # an unset field, or equinox's "no wrapper fields" marker
    raise Uncacheable(f"static value of type {type(value).__qualname__} cannot be keyed")


_MISSING = object()
