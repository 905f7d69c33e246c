"""`gearjax run`: simulate a scene file (default: the built-in scene) and report it."""

from __future__ import annotations

import argparse
import json
import sys

#: the sub-command's help line
HELP = "simulate a scene (default: the built-in seed 001 scene)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", nargs="?", help="TOML scene file (default: the built-in scene)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:
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
