"""`gearjax reproduce`: a source paper's quantities beside gearjax's."""

from __future__ import annotations

import argparse
import json

#: the sub-command's help line
HELP = "a paper's quantities beside gearjax's"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("paper", choices=["curvilinear", "dca"], help="curvilinear: the involute curvilinear-tooth paper; dca: the double-circular-arc meshing-impact paper (Li, Wu, Zhu 2015)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument(
        "--cross-check", action="store_true",
        help="dca: also run the general TCA on the generated surfaces with the seed's pitch error (~2 min)",
    )


def run(args: argparse.Namespace) -> int:
    from ..papers import curvilinear, double_arc

    if args.paper == "dca":
        out = double_arc.reproduce(cross_check=args.cross_check)
        print(json.dumps(out, indent=2) if args.json else double_arc.summary(out))
        return 0
    out = curvilinear.reproduce()
    print(json.dumps(out, indent=2) if args.json else curvilinear.summary(out))
    return 0
