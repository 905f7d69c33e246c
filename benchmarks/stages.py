"""Trace, compile and run time of each pipeline stage, and of the `gearjax run` command.

    python benchmarks/stages.py [--repeats 3] [--quick] [--accuracy fast|default|reference]
                                [--stages ...] [--no-cli]

Stages: the built-in default scene (`gearjax.io.scene_file.default_scene()`: seed 001 pair,
paper optimum, 1000 N·m, 5000 rpm) with its effects and compliance chosen so that
`gj.simulate` runs up to the stage measured:

| stage | scene | simulate runs |
|---|---|---|
| tca_unmodified | no torque, no modification, `tca_method="surface"` | TCA of the bare flanks |
| tca_surface | no torque, `tca_method="surface"` | TCA (general, on the real flanks) |
| tca_plane_of_action | no torque, `tca_method="plane_of_action"` | TCA (involute fast path) |
| ltca_iso | torque, `IsoCompliance()` | surface TCA + LTCA |
| ltca_slice | torque, `SliceCompliance()` | surface TCA + LTCA |
| impact | the default scene (`effects=["impact"]`, slice compliance) | TCA + LTCA + impact |

Each stage is `jax.jit(lambda d: gj.simulate(combine(d, static), throw=False))` on the
scene's arrays, timed phase by phase (`.trace`, `.lower`, `.compile`, first run, median
of steady runs), in a fresh process per repeat: JAX caches traces within a process, so a
second stage in the same process would time the cache. The persistent compilation cache
is off there. A stage's own cost is its row minus the row it builds on (`increment`).

`python benchmarks/stages.py --stages tca_unmodified tca_surface ltca_slice impact --no-cli
--name effects` gives one row per scene kind (rigid unmodified, rigid modified, loaded,
loaded with impact): what each effect costs when a scene asks for it.

CLI: wall time of `python -m gearjax.cli run` (the `gearjax run` command, import
included) on the default scene, cold (a fresh empty `GEARJAX_CACHE_DIR` in a temporary
directory) and warm (a second run with the same directory, which loads the compiled
program from JAX's persistent cache).

Values are medians over `--repeats` fresh processes. `--quick` (a smoke test, not a
measurement) uses the "fast" accuracy preset, also for the CLI through a scene file that
is the default scene with `accuracy = "fast"`, and writes stages_quick.json. Results:
benchmarks/results/stages.json, written after every stage.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))

#: The stages in pipeline order, and the stage each one builds on (for the increment).
STAGES = {
    "tca_unmodified": None,
    "tca_surface": "tca_unmodified",
    "tca_plane_of_action": None,
    "ltca_iso": "tca_surface",
    "ltca_slice": "tca_surface",
    "impact": "ltca_slice",
}
PHASES = ("trace_s", "lower_s", "compile_s", "first_run_s", "run_s")
#: line prefix of a child process's result
TAG = "STAGE_RESULT "


# --------------------------------------------------------------------------- child
def stage_scene(stage: str, accuracy: str):
    """The default scene, set up so that `simulate` runs up to `stage`."""
    import gearjax as gj
    from gearjax.io.scene_file import default_scene

    scene, _ = default_scene()
    acc = scene.accuracy if accuracy == "default" else gj.Accuracy.preset(accuracy)
    rigid = gj.OperatingPoint(speed=scene.operating.speed)
    if stage == "tca_unmodified":
        return dataclasses.replace(scene, modification=None, operating=rigid, effects=frozenset(),
                                   accuracy=acc.replace(tca_method="surface"))
    if stage == "tca_surface":
        return dataclasses.replace(scene, operating=rigid, effects=frozenset(), accuracy=acc.replace(tca_method="surface"))
    if stage == "tca_plane_of_action":
        return dataclasses.replace(
            scene, operating=rigid, effects=frozenset(), accuracy=acc.replace(tca_method="plane_of_action")
        )
    if stage == "ltca_iso":
        return dataclasses.replace(scene, effects=frozenset(), compliance=gj.IsoCompliance(), accuracy=acc)
    if stage == "ltca_slice":
        return dataclasses.replace(scene, effects=frozenset(), compliance=gj.SliceCompliance(), accuracy=acc)
    if stage == "impact":
        return dataclasses.replace(scene, effects=frozenset({"impact"}), accuracy=acc)
    raise ValueError(f"unknown stage {stage!r}; known: {list(STAGES)}")


def measure_stage(stage: str, accuracy: str, runs: int) -> dict:
    """Trace, lower, compile, first run and median steady run of one stage (this process)."""
    import equinox as eqx
    import jax

    import gearjax as gj

    jax.config.update("jax_enable_x64", True)
    from _common import count_equations

    scene = stage_scene(stage, accuracy)
    dynamic, static = eqx.partition(scene, eqx.is_array)
    fn = jax.jit(lambda d: gj.simulate(eqx.combine(d, static), throw=False))
    t0 = time.perf_counter()
    traced = fn.trace(dynamic)
    t1 = time.perf_counter()
    lowered = traced.lower()
    t2 = time.perf_counter()
    compiled = lowered.compile()
    t3 = time.perf_counter()
    result = jax.block_until_ready(compiled(dynamic))
    t4 = time.perf_counter()
    steady = []
    for _ in range(runs):
        t = time.perf_counter()
        jax.block_until_ready(compiled(dynamic))
        steady.append(time.perf_counter() - t)
    failed = [
        name for name in ("ltca", "impact")
        if getattr(result, name) is not None and bool((getattr(result, name).result != gj.RESULTS.successful).any())
    ]
    return {
        "stage": stage,
        "effects": sorted(scene.effects),
        "compliance": type(scene.compliance).__name__ if "ltca" in scene.effects else None,
        "tca_method": scene.accuracy.tca_method,
        "jaxpr_equations": count_equations(traced.jaxpr.jaxpr),
        "trace_s": t1 - t0,
        "lower_s": t2 - t1,
        "compile_s": t3 - t2,
        "first_run_s": t4 - t3,
        "run_s": statistics.median(steady),
        "failed_stages": failed,
    }


# --------------------------------------------------------------------------- parent
def _env(**extra) -> dict:
    """Environment of the children: this checkout's gearjax first on the path, and no
    persistent compilation cache unless asked for."""
    env = {k: v for k, v in os.environ.items() if k not in ("JAX_COMPILATION_CACHE_DIR", "GEARJAX_CACHE_DIR")}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    env.update(extra)
    return env


def run_stage_child(stage: str, accuracy: str, runs: int) -> dict:
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", stage, "--accuracy", accuracy, "--runs", str(runs)]
    proc = subprocess.run(cmd, env=_env(), capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"stage {stage} failed (exit {proc.returncode}):\n{proc.stderr[-4000:]}")
    lines = [line for line in proc.stdout.splitlines() if line.startswith(TAG)]
    return json.loads(lines[-1][len(TAG):])


def run_cli(cache_dir: Path, scene_file: Path | None) -> float:
    """Wall time (s) of one `gearjax run` process, import included."""
    cmd = [sys.executable, "-m", "gearjax.cli", "run"] + ([str(scene_file)] if scene_file else [])
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=_env(GEARJAX_CACHE_DIR=str(cache_dir)), capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"gearjax run failed (exit {proc.returncode}):\n{proc.stderr[-4000:]}")
    return wall


def _directory_size(path: Path) -> tuple[int, int]:
    files = [p for p in path.rglob("*") if p.is_file()]
    return len(files), sum(p.stat().st_size for p in files)


def measure_cli(repeats: int, quick: bool) -> dict:
    """Cold and warm `gearjax run` of the default scene (fast accuracy with `quick`)."""
    runs = {"cold_s": [], "warm_s": []}
    entries = []
    with tempfile.TemporaryDirectory(prefix="gearjax_stages_") as tmp:
        scene_file = None
        if quick:
            from gearjax.io.scene_file import DEFAULT_SCENE_TOML

            text = DEFAULT_SCENE_TOML.replace('accuracy = "default"', 'accuracy = "fast"')
            if text == DEFAULT_SCENE_TOML:
                raise RuntimeError("could not set the fast accuracy in the default scene file")
            scene_file = Path(tmp) / "default_fast.toml"
            scene_file.write_text(text)
        for r in range(repeats):
            cache = Path(tmp) / f"cache{r}"  # fresh and empty: gearjax creates it
            runs["cold_s"].append(run_cli(cache, scene_file))
            entries.append(_directory_size(cache))
            runs["warm_s"].append(run_cli(cache, scene_file))
            shutil.rmtree(cache, ignore_errors=True)
            print(f"  gearjax run: cold {runs['cold_s'][-1]:.1f} s, warm {runs['warm_s'][-1]:.1f} s "
                  f"(cache {entries[-1][0]} files, {entries[-1][1] / 1e6:.1f} MB)", flush=True)
    return {
        "command": f"{Path(sys.executable).name} -m gearjax.cli run" + (" default_fast.toml" if quick else ""),
        "scene": "default" + (" with accuracy = 'fast'" if quick else ""),
        "cold_s": statistics.median(runs["cold_s"]),
        "warm_s": statistics.median(runs["warm_s"]),
        "runs": runs,
        "cache_files_after_cold": [n for n, _ in entries],
        "cache_bytes_after_cold": [b for _, b in entries],
    }


def _median_rows(samples: list[dict]) -> dict:
    row = {k: samples[0][k] for k in ("stage", "effects", "compliance", "tca_method", "jaxpr_equations")}
    for phase in PHASES:
        row[phase] = statistics.median(s[phase] for s in samples)
        row[phase.removesuffix("_s") + "_runs_s"] = [s[phase] for s in samples]
    row["failed_stages"] = sorted(set().union(*(s["failed_stages"] for s in samples)))
    return row


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=3, help="fresh processes per stage and CLI mode (median)")
    parser.add_argument("--quick", action="store_true", help="'fast' accuracy everywhere (smoke test)")
    parser.add_argument("--accuracy", default=None, help="accuracy preset of the stages (default: default, "
                        "or fast with --quick)")
    parser.add_argument("--stages", nargs="*", default=list(STAGES), choices=list(STAGES))
    parser.add_argument("--no-cli", action="store_true", help="skip the gearjax run timings")
    parser.add_argument("--runs", type=int, default=5, help="steady runs per process (median)")
    parser.add_argument("--name", default=None, help="results file benchmarks/results/NAME.json")
    parser.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    accuracy = args.accuracy or ("fast" if args.quick else "default")

    if args.child:
        print(TAG + json.dumps(measure_stage(args.child, accuracy, args.runs)), flush=True)
        return

    from _common import machine, write

    import gearjax  # noqa: F401  (before `machine()` starts JAX's backends: it sets an XLA flag)

    name = args.name or ("stages_quick" if args.quick else "stages")
    out = {"machine": machine(), "quick": args.quick, "accuracy": accuracy, "repeats": args.repeats,
           "steady_runs": args.runs, "scene": "default (seed 001, paper optimum, 1000 N m, 5000 rpm)",
           "stages": [], "cli": None}
    rows = {}
    for stage in args.stages:
        samples = []
        for _ in range(args.repeats):
            samples.append(run_stage_child(stage, accuracy, args.runs))
        rows[stage] = row = _median_rows(samples)
        base = STAGES[stage]
        if base in rows:
            row["increment_over"] = base
            for phase in ("compile_s", "run_s"):
                row[f"increment_{phase}"] = row[phase] - rows[base][phase]
        out["stages"].append(row)
        write(name, out)
        print(f"{stage:20s} eqns {row['jaxpr_equations']:7d}  trace {row['trace_s']:6.2f} s  lower "
              f"{row['lower_s']:6.2f} s  compile {row['compile_s']:6.2f} s  first run {row['first_run_s']:7.3f} s  "
              f"run {row['run_s']:8.4f} s" + (f"  FAILED: {row['failed_stages']}" if row["failed_stages"] else ""),
              flush=True)
    if not args.no_cli:
        out["cli"] = measure_cli(args.repeats, args.quick)
        write(name, out)
    path = write(name, out)

    print(f"\n{'quick smoke run, not a measurement; ' if args.quick else ''}accuracy {accuracy!r}; median of "
          f"{args.repeats} fresh processes (steady run: median of {args.runs} in each)")
    print("\n| stage | jaxpr equations | trace (s) | lower (s) | compile (s) | first run (s) | run (s) | "
          "compile / run over the stage before (s) |")
    print("|---|---:|---:|---:|---:|---:|---:|---|")
    for r in out["stages"]:
        inc = (f"+{r['increment_compile_s']:.1f} / +{r['increment_run_s']:.4f} over {r['increment_over']}"
               if "increment_over" in r else "")
        print(f"| {r['stage']} | {r['jaxpr_equations']} | {r['trace_s']:.2f} | {r['lower_s']:.2f} | "
              f"{r['compile_s']:.2f} | {r['first_run_s']:.3f} | {r['run_s']:.4f} | {inc} |")
    if out["cli"]:
        c = out["cli"]
        print(f"\n`{c['command']}` ({c['scene']}), import included: cold {c['cold_s']:.1f} s (empty "
              f"GEARJAX_CACHE_DIR), warm {c['warm_s']:.1f} s (same directory)")
        if not all(c["cache_files_after_cold"]):
            print("warning: the cold run left the cache directory empty: the program was not cached")
    print(f"written {path}")


if __name__ == "__main__":
    main()
