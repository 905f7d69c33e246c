"""Long impact sweeps in chunks that lose nothing, and the sweep's results in the usual units.

`run_impact_sweep` splits the torque axis of a torque × speed grid into chunks of equal
length (the last one padded by repeating its last torque, the padded rows dropped), so
every chunk runs the same compiled `impact_sweep` program and only one chunk's arrays are
in memory at a time. With a run directory it holds

* `run.json`: what the sweep is (scene digest, accuracy, torques, speeds, chunk length),
  written once; a resumed run must match it;
* `history.jsonl`: one line per finished chunk with its rows (the per-torque results in
  the usual units), appended and flushed to disk (`fsync`) as soon as the chunk is done;
* `state.npz`: the number of finished chunks, replaced atomically after the line;
* `sweep.json` and `sweep.npz`: the whole grid, written when the last chunk is done.

A killed run resumed with `resume=True` (`gearjax sweep --resume`) drops a line cut by the
kill, keeps the finished chunks and runs the others: each chunk is one deterministic
compiled program, so the result equals that of an uninterrupted run.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from pathlib import Path

import equinox as eqx
import jax
import numpy as np

from .._validate import check_int
from ..io.progress import Progress, compiling
from ..io.rundir import RunDirectory, atomic_write
from ..scene import Scene, check_one_zone

#: Keys of `sweep_rows` whose values have one entry per torque (the rest are per run).
_PER_RUN = ("speed_rpm", "accuracy", "wall_time_s", "chunks", "chunk_length", "files")


def run_impact_sweep(
    scene: Scene,
    torques_Nm,
    speeds_rpm,
    *,
    chunk: int | None = None,
    out: str | os.PathLike | None = None,
    resume: bool = False,
    progress: str | None = None,
) -> dict:
    """`impact_sweep` of a torque × speed grid in chunks of `chunk` torques, each finished
    chunk written to `out` before the next starts (see the module docstring).

    Args:
        scene: a scene with "impact" in its effects; its own operating point is ignored.
        torques_Nm: pinion torques (N·m), a non-empty 1-D list of finite values >= 0.
        speeds_rpm: pinion speeds (rpm), the same.
        chunk: torques per chunk, an integer >= 1 (default: all in one chunk). Every
            chunk holds `chunk` torques × all speeds; memory grows with it.
        out: run directory; None keeps the results in memory only (no resume).
        resume: continue the run in `out` (it must describe the same sweep).
        progress: "auto" (a tqdm bar on a terminal: chunks done, grid points/s, time
            left; plain lines otherwise), "bar", "lines" or None.

    Returns:
        The sweep as `sweep_rows` describes it: lists per torque (nested [torque][speed]
        for the impact), plus `speed_rpm`, `accuracy`, `wall_time_s` (the run's, resumed
        parts included), `chunks`, `chunk_length`, `files`.
    """
    from ._axes import _speeds, _torques

    _torques(None, torques_Nm), _speeds(None, speeds_rpm)  # impact_sweep's checks, before any work
    torques_Nm, speeds_rpm = np.asarray(torques_Nm, dtype=float), np.asarray(speeds_rpm, dtype=float)
    if "impact" not in scene.effects:
        raise ValueError("run_impact_sweep needs a scene with effects including 'impact' (and so a torque)")
    check_one_zone(scene, "an impact sweep")
    count = torques_Nm.shape[0]
    length = count if chunk is None else check_int("chunk", chunk, 1)
    length = min(length, count)
    chunks = -(-count // length)
    if resume and out is None:
        raise ValueError("resume needs a run directory (out)")
    accuracy = _accuracy_name(scene)
    directory, records = _resume(out, resume, {
        "kind": "impact_sweep",
        "scene_sha256": scene_digest(scene),
        "accuracy": accuracy,
        "torque_Nm": torques_Nm.tolist(),
        "speed_rpm": speeds_rpm.tolist(),
        "chunk_length": length,
    })
    start = time.perf_counter()
    previous = records[-1]["elapsed_s"] if records else 0.0
    bar = Progress(progress, chunks, len(records), "chunk")
    try:
        for k in range(len(records), chunks):
            first = k == len(records)  # the chunk that compiles the sweep's program
            rows = _chunk_rows(scene, torques_Nm[k * length:(k + 1) * length], length, speeds_rpm,
                               progress if first else None)
            elapsed = previous + time.perf_counter() - start
            record = {"step": k + 1, "rows": rows, "elapsed_s": elapsed}
            records.append(record)
            if directory is not None:
                directory.save({"chunks": np.asarray(k + 1, np.int32)}, record)
            points = sum(len(r["rows"]["torque_Nm"]) for r in records) * speeds_rpm.shape[0]
            bar.update(k + 1, elapsed, points_per_s=f"{points / max(elapsed, 1e-9):.3g}")
    finally:
        bar.close()
    report = {key: [v for r in records for v in r["rows"][key]] for key in records[0]["rows"]}
    report |= {
        "speed_rpm": speeds_rpm.tolist(),
        "accuracy": accuracy,
        "wall_time_s": previous + time.perf_counter() - start,
        "chunks": chunks,
        "chunk_length": length,
        "files": [],
    }
    if directory is not None:
        report["files"] = write_results(report, directory.path)
    return report


def _resume(out, resume, description) -> tuple[RunDirectory | None, list[dict]]:
    """The run directory (None without `out`) and the chunk records finished before."""
    if out is None:
        return None, []
    directory = RunDirectory(out, description, resume)
    loaded = directory.load({"chunks": np.zeros((), np.int32)}) if resume else None
    return directory, [] if loaded is None else loaded[1]


def _chunk_rows(scene, torques_Nm, length, speeds_rpm, progress) -> dict:
    """`sweep_rows` of one chunk: `torques_Nm` padded to `length` (one program for every
    chunk) and swept, the padding dropped; `progress` announces the compilation."""
    from .loads import impact_sweep

    padded = np.concatenate([torques_Nm, np.repeat(torques_Nm[-1:], length - torques_Nm.shape[0])])
    with compiling("the impact sweep's program for this scene structure and chunk", mode=progress):
        sweep = impact_sweep(scene, torques_Nm=padded, speeds_rpm=speeds_rpm, throw=False)
    return {key: value[: torques_Nm.shape[0]] for key, value in sweep_rows(sweep).items() if key not in _PER_RUN}


def sweep_rows(sweep) -> dict:
    """An `ImpactSweep` in the usual units (keys in the README): lists per torque, nested
    [torque][speed] for the impact, and `speed_rpm`."""
    from .._solution import RESULTS, enum_name

    imp, ltca = sweep.impact, sweep.ltca
    rb2 = float(np.asarray(ltca.action_radius).reshape(-1, 2)[0, 1])
    lte = np.asarray(ltca.transmission_error)
    return {
        "torque_Nm": np.asarray(sweep.torques_Nm).tolist(),
        "speed_rpm": np.asarray(sweep.speeds_rpm).tolist(),
        "impact_force_N": np.asarray(imp.force).tolist(),
        "impact_velocity_mm_per_s": np.asarray(imp.velocity).tolist(),
        "impact_regime": np.asarray(enum_name(imp.regime)).tolist(),
        "impact_contact_kind": np.asarray(enum_name(imp.kind)).tolist(),
        "impact_pinion_roll_length_mm": np.asarray(imp.pinion_parameter).tolist(),
        "impact_face_position_mm": np.asarray(imp.slice_z).tolist(),
        "impact_pinion_angle_deg": np.degrees(np.asarray(imp.pinion_angle)).tolist(),
        "impact_converged": np.asarray(imp.result == RESULTS.successful).tolist(),
        "impact_result": np.asarray(enum_name(imp.result)).tolist(),
        "stiffness_exponent": np.asarray(imp.stiffness.exponent)[:, 0].tolist(),
        "lte_peak_to_peak_um": (np.asarray(ltca.lte_peak_to_peak_line) * 1e3).tolist(),
        "lte_mean_um": (lte.mean(axis=-1) * rb2 * 1e3).tolist(),
        "ltca_converged": np.asarray(ltca.result == RESULTS.successful).tolist(),
    }


def write_results(report: dict, directory: Path) -> list[str]:
    """`sweep.json` ({"sweep": report}) and `sweep.npz` (its lists as arrays), each written
    atomically; returns their paths."""
    files = [str(directory / "sweep.json"), str(directory / "sweep.npz")]
    atomic_write(directory / "sweep.json", json.dumps({"sweep": report | {"files": files}}, indent=2).encode())
    tmp = directory / "sweep.tmp.npz"
    with open(tmp, "wb") as f:
        np.savez(f, **{k: np.asarray(v) for k, v in report.items() if isinstance(v, list) and k != "files"})
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, directory / "sweep.npz")
    return files


def scene_digest(scene: Scene) -> str:
    """SHA-256 of everything a scene holds (static settings and array values), equal across
    processes for equal scenes: a resumed sweep checks it."""
    from ..runtime.program_key import canon

    host = jax.tree_util.tree_map(lambda x: np.asarray(x) if eqx.is_array(x) else x, scene)
    return hashlib.sha256(repr(canon(host)).encode()).hexdigest()


def _accuracy_name(scene: Scene) -> str:
    from ..optimize.certification import accuracy_name

    return accuracy_name(scene.accuracy)

