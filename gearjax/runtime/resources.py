"""Memory a scene's compiled program needs, estimated before compiling, and the guard that
refuses a scene that cannot fit.

The arrays that grow fastest are the loaded contact's: for every position (all at once,
`vmap`) and tooth pair, the (S × S) block of the slices' mutual compliances and the Newton
matrices built from it, S = face_slices + 2 (the face ends are edge candidates). The TCA
and the per-point arrays grow linearly in S. So, for P = positions_per_pitch × pitches
positions and K tooth pairs,

$$M \\approx c_1\\,P\\,K\\,S \\cdot 8\\ \\text{bytes} + c\\,P\\,K\\,S^2 \\cdot 8\\ \\text{bytes}$$

for a loaded scene (the first term alone for a rigid one), in float64 (half in float32),
times the number of loads a sweep batches. The constants are XLA's own plan for the
program (`Compiled.memory_analysis()`, temporary buffers) of the default scene at 1000 N·m
with 81, 161 and 21 face slices (P = 32, K = 5): 51.3 MB at S = 83 and 201.1 MB at
S = 163 give $c = (201.1 - 51.3)\\,\\text{MB} / ((163^2 - 83^2) P K \\cdot 8) = 5.9$, and the
8.6 MB at S = 23 less its quadratic part gives $c_1 = 156$. `benchmarks/studies/memory_model.py`
recomputes them and checks the estimate against the measured peak memory of two larger
scenes (README, "Memory guard").

The guard compares the estimate with the memory of the device that will run the program
(a GPU's `bytes_limit`, the machine's physical memory on a CPU) and raises a `ValueError`
that names the knobs and the largest face-slice count that fits.
"""

from __future__ import annotations

import os

import jax

#: Words (8 bytes in float64) per position, tooth pair and slice pair in the LTCA's
#: compliance and Newton blocks, from XLA's memory plan (module docstring).
LTCA_WORDS_PER_SLICE_PAIR = 5.9
#: Words per position, tooth pair and slice of the arrays linear in the slices.
TCA_WORDS_PER_SLICE = 156.0
#: What the guard may use of the device's memory.
USABLE_FRACTION = 0.8


class MemoryEstimateError(ValueError):
    """A scene whose program would not fit in memory; the message names the knobs."""


def estimate_bytes(scene, loads: int = 1) -> float:
    """Estimated peak memory (bytes) of `simulate(scene)`'s program, `loads` loads batched
    (a sweep); see the module docstring for the model."""
    acc = scene.accuracy
    positions = acc.positions_per_pitch * scene.pitches
    pairs = len(scene.pairs)
    slices = acc.face_slices + 2
    word = 8 if acc.dtype == "float64" else 4
    total = TCA_WORDS_PER_SLICE * positions * pairs * slices * word
    if "ltca" in scene.effects:
        total += loads * LTCA_WORDS_PER_SLICE_PAIR * positions * pairs * slices**2 * word
    return total


def available_bytes() -> float:
    """Memory the program may use: `USABLE_FRACTION` of the default device's `bytes_limit`
    (GPU), or of the machine's physical memory (CPU); `GEARJAX_MEMORY_LIMIT_GB` overrides."""
    limit = os.environ.get("GEARJAX_MEMORY_LIMIT_GB")
    if limit:
        return float(limit) * 1e9
    stats = None
    try:
        stats = jax.devices()[0].memory_stats()
    except Exception:  # noqa: BLE001 - CPU backends may not report; fall back to the host
        stats = None
    if stats and stats.get("bytes_limit"):
        return USABLE_FRACTION * float(stats["bytes_limit"])
    return USABLE_FRACTION * os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def check_memory(scene, loads: int = 1, what: str = "simulate", batch: int = 1) -> None:
    """Raise `MemoryEstimateError` if the estimate (times `batch` designs computed at once)
    exceeds `available_bytes()`, naming the knobs (face_slices, positions_per_pitch, the
    tooth pairs, the loads, the designs) and the largest face-slice count that would fit."""
    needed = batch * estimate_bytes(scene, loads)
    limit = available_bytes()
    if needed <= limit:
        return
    acc = scene.accuracy
    fits = acc.face_slices
    while fits > 1 and batch * estimate_bytes(_with_slices(scene, fits), loads) > limit:
        fits = max(1, int(fits * 0.9))
    at_once = f" for {loads} loads at once" if loads > 1 else ""
    at_once += f" for {batch} designs at once" if batch > 1 else ""
    raise MemoryEstimateError(
        f"{what}: the scene's program needs an estimated {needed / 1e9:.1f} GB{at_once}, more than the "
        f"{limit / 1e9:.1f} GB it may use here: accuracy.face_slices = {acc.face_slices} (memory grows with its "
        f"square), positions_per_pitch = {acc.positions_per_pitch} x pitches = {scene.pitches}, "
        f"{len(scene.pairs)} tooth pairs. Lower face_slices (at most {fits} fit) or positions_per_pitch"
        + (", or sweep fewer loads at once (gearjax sweep --chunk)" if loads > 1 else "")
        + (", or compute fewer designs at once (batch_size)" if batch > 1 else "")
        + "; GEARJAX_MEMORY_LIMIT_GB overrides the limit."
    )


def _with_slices(scene, slices: int):
    import dataclasses

    return dataclasses.replace(scene, accuracy=scene.accuracy.replace(face_slices=slices))
