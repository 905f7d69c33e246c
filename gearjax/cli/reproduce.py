"""`gearjax reproduce`: a source paper's quantities beside gearjax's."""

from __future__ import annotations

import argparse
import json
import sys

#: the sub-command's help line
HELP = "a paper's quantities beside gearjax's"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("paper", choices=["curvilinear", "dca"], help="curvilinear: the involute curvilinear-tooth paper; dca: the double-circular-arc meshing-impact paper (Li, Wu, Zhu 2015)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument(
        "--cross-check", action="store_true",
        help="dca: also run the general TCA on the generated surfaces with the seed's pitch error (~2 min)",
    )
    parser.add_argument(
        "--accuracy", metavar="SPEC",
        help="dca: the meshing stiffness's accuracy, PRESET or PRESET@PxS (positions per pitch x face slices); "
             "default: default@64x41, converged to 0.06 %%",
    )


def run(args: argparse.Namespace) -> int:
    from ..accuracy import Accuracy
    from ..papers import curvilinear, double_arc

    if args.accuracy is not None and args.paper != "dca":
        print("gearjax: error: --accuracy applies to `reproduce dca` only", file=sys.stderr)
        return 2

    if args.paper == "dca":
        accuracy = double_arc.STIFFNESS_ACCURACY if args.accuracy is None else args.accuracy
        try:
            Accuracy.from_spec(accuracy)
        except ValueError as error:
            print(f"gearjax: error: --accuracy: {error}", file=sys.stderr)
            return 2
        out = double_arc.reproduce(cross_check=args.cross_check, accuracy=accuracy)
        print(json.dumps(out, indent=2) if args.json else double_arc.summary(out))
        return 0
    out = curvilinear.reproduce()
    print(json.dumps(out, indent=2) if args.json else curvilinear.summary(out))
    return 0
