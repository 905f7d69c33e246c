"""Sharded sweeps against one device, on forced CPU host devices.

    python benchmarks/studies/check_sharding.py [--devices 4] [--timeout 600]

Runs, in a subprocess with `XLA_FLAGS=--xla_force_host_platform_device_count=N`, the seed
001 default scene at `fast`: `impact_sweep` of 3 torques × 2 speeds on one device and with
`devices="all"` (padded to N), and `design_sweep` of 3 designs × 2 torques on one device and
on 2 devices; prints the largest relative differences and exits 1 if any exceeds 1e-9.

Not in the test suite: every device compiles the sweep program for itself (~2 min on 4
forced devices on this 2-core machine), and forced host devices once hung jaxlib 0.10.2's
CPU runtime even in an unsplit call (README, "Sweeps"); a hang in CI would cost the whole
run, so the check is a tool with a timeout.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

SCRIPT = """
import json, jax
jax.config.update("jax_enable_x64", True)
import equinox as eqx, numpy as np
from gearjax.io.scene_file import DEFAULT_SCENE_TOML, parse_scene
from gearjax.sweep import design_sweep, impact_sweep
from gearjax._solution import enum_name
scene, _ = parse_scene(DEFAULT_SCENE_TOML.replace('accuracy = "default"', 'accuracy = "fast"'))
t, n = [300.0, 700.0, 1600.0], [2500.0, 5000.0]
one = impact_sweep(scene, torques_Nm=t, speeds_rpm=n)
many = impact_sweep(scene, torques_Nm=t, speeds_rpm=n, devices="all")
designs = [eqx.tree_at(lambda s: s.modification.root_relief, scene, f * scene.modification.root_relief) for f in (0.0, 1.0, 3.0)]
rows = design_sweep(designs, torques_Nm=t[:2])
split = design_sweep(designs, torques_Nm=t[:2], devices=jax.devices()[:2])
print(json.dumps({"devices": jax.device_count(),
                  "force": [np.asarray(one.impact.force).tolist(), np.asarray(many.impact.force).tolist()],
                  "regime": [enum_name(one.impact.regime).tolist(), enum_name(many.impact.regime).tolist()],
                  "lte": [np.asarray(rows.ltca.lte_peak_to_peak_line).tolist(), np.asarray(split.ltca.lte_peak_to_peak_line).tolist()]}))
"""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--devices", type=int, default=4)
    parser.add_argument("--timeout", type=float, default=600.0)
    args = parser.parse_args()
    env = dict(os.environ, XLA_FLAGS=f"--xla_force_host_platform_device_count={args.devices}")
    try:
        out = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=args.timeout, env=env)
    except subprocess.TimeoutExpired:
        print(f"check_sharding: no result within {args.timeout:g} s (the CPU runtime hang described above)")
        return 1
    if out.returncode != 0:
        print(out.stderr[-3000:])
        return 1
    import numpy as np

    got = json.loads(out.stdout.strip().splitlines()[-1])
    force = abs(np.asarray(got["force"][1]) / np.asarray(got["force"][0]) - 1).max()
    lte = abs(np.asarray(got["lte"][1]) / np.asarray(got["lte"][0]) - 1).max()
    same_regime = got["regime"][0] == got["regime"][1]
    print(f"devices {got['devices']}: impact_sweep force rel. diff {force:.2e}, regimes equal {same_regime}; "
          f"design_sweep LTE p-p rel. diff {lte:.2e}")
    return 0 if force <= 1e-9 and lte <= 1e-9 and same_regime else 1


if __name__ == "__main__":
    raise SystemExit(main())
