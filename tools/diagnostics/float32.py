"""The float32 seed pair of `tests/test_hard_cases.py`: the `fast`
scene at the paper optimum, 1000 N·m, pairs -2..2, in float32 and float64; prints the
unconverged TCA solves, the missed contacts (`tests/_cases.missed_contacts`), the LTCA and
impact results and how far the float32 LTE mean and impact force are from float64."""
import sys

sys.path.insert(0, "tests")
import jax

jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp
import numpy as np

import gearjax as gj
from _cases import PAPER_UM, bad_fields, helical, missed_contacts, scene

out = {}
for dtype in ("float32", "float64"):
    s = scene(helical(), PAPER_UM / 1000.0, pairs=(-2, -1, 0, 1, 2),
              accuracy=gj.Accuracy.preset("fast").replace(dtype=dtype))
    r = out[dtype] = gj.simulate(s, throw=False)
    unconverged = np.asarray(r.tca.unconverged)
    print(dtype, "| non-finite:", bad_fields(r), "| missed contacts:", missed_contacts(r),
          "| unconverged solves:", int(unconverged.sum()), "on", int((unconverged > 0).sum()), "slices",
          "of", unconverged.size, "| LTCA:", gj.enum_name(r.ltca.result),
          "| impact:", gj.enum_name(r.impact.result), f"({int(r.impact.search_steps)} search steps)",
          "| LTE mean", f"{float(jnp.mean(r.ltca.transmission_error)):.4e} rad",
          "| force", f"{float(r.impact.force):.1f} N", gj.enum_name(r.impact.regime), flush=True)
a, b = out["float32"], out["float64"]
print(f"float32 vs float64: LTE mean {float(jnp.mean(a.ltca.transmission_error)) / float(jnp.mean(b.ltca.transmission_error)) - 1:+.1%}, "
      f"impact force {float(a.impact.force) / float(b.impact.force) - 1:+.1%}")
