"""The command line's programs are cacheable: a second process loads the compiled program
from JAX's persistent compilation cache (counted from JAX's own monitoring events)."""

import json
import os
import subprocess
import sys
import textwrap

SCENE = """\
[pair]
teeth = [23, 41]
normal_module = 4.0
helix_angle_deg = 12.0
face_width = 20.0

[modification]
tip_relief_um = 8.0
tip_relief_length = 3.0

[analysis]
accuracy = "fast"
"""

PROBE = textwrap.dedent(
    """
    import json, sys
    import jax.monitoring
    counts = {}
    def listen(event, **kwargs):
        counts[event] = counts.get(event, 0) + 1
    jax.monitoring.register_event_listener(listen)
    from gearjax.cli import main
    code = main(["run", sys.argv[1], "--json"] + sys.argv[2:])
    print("EVENTS " + json.dumps(counts), file=sys.stderr)
    sys.exit(code)
    """
)


def _run(scene, cache_dir, *extra):
    env = dict(os.environ, GEARJAX_CACHE_DIR=str(cache_dir))
    out = subprocess.run(
        [sys.executable, "-c", PROBE, str(scene), *extra], env=env, capture_output=True, text=True, timeout=900
    )
    assert out.returncode == 0, out.stderr[-2000:]
    line = [x for x in out.stderr.splitlines() if x.startswith("EVENTS ")][-1]
    return json.loads(out.stdout), json.loads(line[len("EVENTS "):])


def test_second_run_loads_the_program_from_the_cache(tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE)
    cache = tmp_path / "cache"
    first, events1 = _run(scene, cache)
    assert events1.get("/jax/compilation_cache/cache_hits", 0) == 0
    assert any(cache.iterdir()), "the first run wrote no program to the cache"
    second, events2 = _run(scene, cache)
    assert events2.get("/jax/compilation_cache/cache_hits", 0) >= 1
    assert second["tca"]["te_um"] == first["tca"]["te_um"]  # the same program, the same numbers
    # --no-cache: the warm cache is not read
    _, events3 = _run(scene, cache, "--no-cache")
    assert events3.get("/jax/compilation_cache/cache_hits", 0) == 0
