r"""Derived geometry, resolved once.

Quantities that depend on the pair only (working pressure angle — an inverse-involute
Newton solve —, centre distance, radii, placements) are `derived` properties.
`pair.resolve()` evaluates them once and returns a pair that carries their values (field
`derived`); every stage resolves its pair on entry, so the residuals of the contact
solves read constants instead of re-tracing their formulas (as lineax's
`init`/`compute` split does). Gradients flow through `resolve()` like through any other
computation. Edit an unresolved pair (e.g. with `eqx.tree_at`): a resolved pair keeps the
values it was resolved with.
"""

import functools

import equinox as eqx

from .._validate import is_concrete


def derived(method):
    """A property of a gear pair that depends on its parameters only.

    Evaluated from the formula on an unresolved pair; read from `pair.derived` on a pair
    returned by `resolve()`.
    """
    name = method.__name__

    @functools.wraps(method)
    def getter(self):
        cache = self.derived
        if cache is not None and name in cache:
            return cache[name]
        return method(self)

    getter.is_derived = True
    return property(getter)


def _derived_names(cls) -> tuple[str, ...]:
    names = []
    for klass in reversed(cls.__mro__):
        for name, value in vars(klass).items():
            if isinstance(value, property) and getattr(value.fget, "is_derived", False) and name not in names:
                names.append(name)
    return tuple(names)


def resolve_derived(pair):
    """`pair` with every `derived` quantity evaluated once (see the module docstring); a
    resolved pair is returned as it is. A pair of concrete arrays (a constructor's checks,
    a scene's) is resolved by one compiled program (`_resolve_compiled`), not by an eager
    program per operation (each compiled once per process); under a transformation the
    quantities are traced into the caller's program."""
    if pair.derived is not None:
        return pair
    if is_concrete(pair):
        return _resolve_compiled(pair)
    return _resolve(pair)


def _resolve(pair):
    resolved = eqx.tree_at(lambda p: p.derived, pair, {}, is_leaf=lambda x: x is None)
    for name in _derived_names(type(pair)):
        # Each quantity is evaluated on the partly resolved pair, so it reuses the
        # ones before it (the working pressure angle is solved once).
        value = getattr(resolved, name)
        resolved = eqx.tree_at(lambda p: p.derived, resolved, {**resolved.derived, name: value})
    return resolved


_resolve_compiled = eqx.filter_jit(_resolve)
