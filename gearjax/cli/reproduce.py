"""`gearjax reproduce`: a source paper's quantities beside gearjax's."""

from __future__ import annotations

import argparse
import json
import sys

#: the sub-command's help line
HELP = "a paper's quantities beside gearjax's"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "paper", choices=["seed001", "curvilinear", "dca"],
        help="seed001: the mesh-in impact of involute helical gears (Table 4; at reference accuracy several "
             "minutes); curvilinear: the involute curvilinear-tooth paper; dca: the double-circular-arc "
             "meshing-impact paper (Li, Wu, Zhu 2015)",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument(
        "--cross-check", action="store_true",
        help="dca: also run the general TCA on the generated surfaces with the seed's pitch error (~2 min)",
    )
    parser.add_argument(
        "--accuracy", metavar="SPEC",
        help="PRESET or PRESET@PxS (positions per pitch x face slices). dca: the meshing stiffness's accuracy, "
             "default default@64x41, converged to 0.06 %%; seed001: default reference, as published",
    )
    parser.add_argument(
        "--check-slices", type=int, metavar="N", default=0,
        help="seed001: evaluate Table 4 again at N face slices and report the largest force difference "
             "(the published table: 161)",
    )


def run(args: argparse.Namespace) -> int:
    from ..accuracy import Accuracy
    from ..papers import curvilinear, double_arc

    from ..papers import seed001

    if args.accuracy is not None and args.paper == "curvilinear":
        print("gearjax: error: --accuracy applies to `reproduce dca` and `reproduce seed001` only", file=sys.stderr)
        return 2
    if args.check_slices and args.paper != "seed001":
        print("gearjax: error: --check-slices applies to `reproduce seed001` only", file=sys.stderr)
        return 2
    if args.check_slices < 0 or args.check_slices > 10000:
        print(f"gearjax: error: --check-slices: must be in [0, 10000]; got {args.check_slices}", file=sys.stderr)
        return 2
    if args.paper in ("dca", "seed001"):
        default = double_arc.STIFFNESS_ACCURACY if args.paper == "dca" else "reference"
        accuracy = default if args.accuracy is None else args.accuracy
        try:
            Accuracy.from_spec(accuracy)
        except ValueError as error:
            print(f"gearjax: error: --accuracy: {error}", file=sys.stderr)
            return 2
    if args.paper == "seed001":
        out = seed001.reproduce(accuracy, args.check_slices)
        print(json.dumps(out, indent=2) if args.json else seed001.summary(out))
        return 0
    if args.paper == "dca":
        out = double_arc.reproduce(cross_check=args.cross_check, accuracy=accuracy)
        print(json.dumps(out, indent=2) if args.json else double_arc.summary(out))
        return 0
    out = curvilinear.reproduce()
    print(json.dumps(out, indent=2) if args.json else curvilinear.summary(out))
    return 0
