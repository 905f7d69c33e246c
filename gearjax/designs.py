r"""Many designs of one gear pair in one compiled call, computing only the outputs asked for.

`simulate_designs(scene, modifications, outputs=...)` is `simulate` mapped over a batch of
flank modifications (and/or mesh errors) of the scene's one pair. The pair stays unbatched
inside the program: its derived geometry, the positions, the face slices and every
design-independent part of the contact grid (on the plane of action, the conjugate contact
points themselves) are computed once, and only what a design changes (its flank depths,
the separations, the loads) is computed per design. This is what `jax.vmap(simulate)` over
`stack_scenes` cannot do, because a stacked scene carries a copy of the pair per design.

`outputs` says what to return, as a function of one design's `SimulationResult` (the
same idea as diffrax's `SaveAt(fn=...)`): the compiled program returns only that, and
XLA drops every computation it does not need (for example the contact points, normals and
sliding velocities of every face slice when only the TE is read).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .geometry.errors import MeshErrors
from .geometry.modification import FlankModification
from .pipeline import STAGES, SimulationResult, check_codes, in_precision, launched, run
from .scene import Scene, check_modification_fits

#: The batched parts of a scene, by `simulate_designs` keyword.
_PARTS = (("modifications", "modification", FlankModification),
          ("gear_modifications", "gear_modification", FlankModification),
          ("errors", "errors", MeshErrors))


def simulate_designs(
    scene: Scene,
    modifications: FlankModification | Sequence[FlankModification] | None = None,
    *,
    gear_modifications: FlankModification | Sequence[FlankModification] | None = None,
    errors: MeshErrors | Sequence[MeshErrors] | None = None,
    outputs: Callable[[SimulationResult], Any] | None = None,
    batch_size: int | None = None,
    throw: bool = True,
) -> Any:
    """`simulate` of `scene` for each design of a batch, the pair resolved once.

    Args:
        scene: the scene: pair, operating point, effects, accuracy; its own modification,
            gear modification or errors are replaced by the batch's where one is given.
        modifications: pinion modifications, one per design: a list, or one
            `FlankModification` whose parameters have a leading design axis (e.g.
            `FlankModification.from_vector(y)` with `y` of shape (designs, 6), mm).
        gear_modifications: gear modifications, likewise.
        errors: mesh errors (`MeshErrors`), likewise.
        outputs: what to return of each design's `SimulationResult`, e.g.
            `lambda r: r.tca.transmission_error`; None returns the whole result. Called
            while tracing, so it must be a JAX function of the result; the program is
            compiled once per `outputs` function object (define it once, not inline in a
            loop).
        batch_size: designs computed at once. None (default) batches all of them
            (`jax.vmap`): best for the plane-of-action TCA and on accelerators. An integer
            runs them in chunks of that size one after another (`jax.lax.map`): on a CPU,
            solver loops batched by `vmap` run to the slowest member, so the surface TCA,
            the LTCA and the impact are usually faster with 1.
        throw: raise `SimulationError` if some design's LTCA or impact failed, or its traced
            modification was out of range (as `simulate`).

    Returns:
        `outputs(result)` with a leading design axis on every array (the whole
        `SimulationResult` when `outputs` is None).

    Raises:
        ValueError: no batch given, a batch of the wrong type, batches of different
            lengths, a modification that does not fit the scene's pair, a `batch_size`
            that is not a positive integer or `outputs` that is not a function; all before
            anything is computed.

    Under `jax.grad`, `jit` or `vmap` (traced designs) the concrete checks are skipped and
    out-of-range designs get NaN outputs and `RESULTS.invalid_modification` (as
    `simulate`).
    """
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a Scene; got {type(scene).__name__}")
    given = {"modifications": modifications, "gear_modifications": gear_modifications, "errors": errors}
    batch = {}
    for keyword, field, kind in _PARTS:
        value = given[keyword]
        if value is not None:
            batch[field] = _stack(keyword, value, kind)
    if not batch:
        raise ValueError("simulate_designs needs a batch: give modifications, gear_modifications or errors")
    count = _count(batch)
    if outputs is not None and not callable(outputs):
        raise ValueError(f"outputs must be a function of a SimulationResult or None; got {type(outputs).__name__}")
    if batch_size is not None and (isinstance(batch_size, bool) or not isinstance(batch_size, int) or batch_size < 1):
        raise ValueError(f"batch_size must be a positive integer or None; got {batch_size!r}")
    for gear, field in ((0, "modification"), (1, "gear_modification")):
        if field in batch:
            check_modification_fits(scene.pair, batch[field], gear, f"{field}s", _relief_coordinates)
    with launched(scene, what="simulate_designs", batch=min(count, batch_size or count)) as prepared:
        out, codes = _simulate_designs(prepared, in_precision(batch, prepared.accuracy), outputs, batch_size)
    if throw:
        check_codes(codes)
    return out


@eqx.filter_jit
def _relief_coordinates(zone, gear: int):
    """`zone.relief_coordinates(gear)` as one compiled call: a batch is usually simulated
    many times over one pair, where eagerly the derived geometry it reads would be many
    small dispatches per call."""
    return zone.relief_coordinates(gear)


def _stack(keyword: str, value, kind):
    """One batched `kind` from a list of them or from one with a leading axis."""
    if isinstance(value, kind):
        stacked = value
    elif isinstance(value, Sequence) and not isinstance(value, str) and value and all(isinstance(v, kind) for v in value):
        stacked = jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *value)
    else:
        raise ValueError(f"{keyword} must be a {kind.__name__} with a leading design axis or a non-empty list of "
                         f"{kind.__name__}; got {type(value).__name__}")
    shapes = {np.shape(leaf) for leaf in jax.tree_util.tree_leaves(stacked)}
    if any(len(shape) != 1 for shape in shapes) or len({shape[0] for shape in shapes}) != 1:
        raise ValueError(f"{keyword}: every parameter must be a 1-D array over the designs, all of one length; "
                         f"got shapes {sorted(shapes)}")
    return stacked


def _count(batch: dict) -> int:
    lengths = {name: jax.tree_util.tree_leaves(part)[0].shape[0] for name, part in batch.items()}
    if len(set(lengths.values())) != 1:
        raise ValueError(f"the batches must hold the same number of designs; got {lengths}")
    return next(iter(lengths.values()))


def _with(scene: Scene, design: dict) -> Scene:
    """`scene` with one design's parts put in."""
    for field, part in design.items():
        scene = eqx.tree_at(lambda s, f=field: getattr(s, f), scene, part, is_leaf=lambda x: x is None)
    return scene


@eqx.filter_jit
def _simulate_designs(scene: Scene, batch: dict, outputs, batch_size):
    """(outputs per design, result codes per stage and design) in one program."""

    def one(design):
        result = run(_with(scene, design))
        codes = {stage: getattr(result, stage).result for stage in STAGES if getattr(result, stage) is not None}
        return (result if outputs is None else outputs(result)), codes

    if batch_size is None:
        return jax.vmap(one)(batch)
    # one design at a time is a plain scan: `batch_size=1` would `vmap` each design, making
    # every solver's condition batched (both branches of each `cond`, selects in each loop)
    return jax.lax.map(one, batch, batch_size=None if batch_size == 1 else batch_size)
