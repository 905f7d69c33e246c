"""The command line's programs are cacheable: a second process loads the traced program from
gearjax's program cache and the compiled one from JAX's persistent compilation cache (counted
from gearjax's and JAX's own counters), and gets the same numbers; the program cache's key
separates what traces differently."""

import json
import math
import os
import pickle
import subprocess
import sys
import textwrap

import jax
import jax.numpy as jnp
import pytest

import gearjax as gj
from gearjax.runtime import program_cache, program_key as _program_key
from gearjax.runtime.versions import gradient_cache_safe
from gearjax.pipeline import prepare as _prepare, simulate_program as _simulate

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
    from gearjax.runtime.program_cache import program_cache_info
    code = main(["run", sys.argv[1], "--json"] + sys.argv[2:])
    counts.update({"program_cache/" + k: v for k, v in program_cache_info().items()})
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


def _files(directory):
    return sorted(str(p.relative_to(directory)) for p in directory.rglob("*") if p.is_file())


def test_second_run_loads_the_program_from_the_cache(tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE)
    cache_dir = tmp_path / "cache"
    first, events1 = _run(scene, cache_dir)
    # (the command stores even its quickest compilations, so a program compiled twice in the
    # first run may already be found there: its misses, not its hits, are what counts)
    assert events1.get("/jax/compilation_cache/cache_misses", 0) >= 1
    assert events1["program_cache/misses"] == 1 and events1["program_cache/writes"] == 1
    assert events1["program_cache/hits"] == 0
    assert any(cache_dir.glob("*-cache")), "the first run wrote no compiled program"
    assert len(list((cache_dir / program_cache.PROGRAMS_SUBDIR).iterdir())) == 1, "the first run wrote no traced program"
    second, events2 = _run(scene, cache_dir)
    # the traced program is loaded, not traced again, and its compilation is found in JAX's cache
    assert events2["program_cache/loads"] == 1 and events2["program_cache/hits"] == 1
    assert events2["program_cache/misses"] == 0 and events2["program_cache/writes"] == 0
    assert events2.get("/jax/compilation_cache/cache_hits", 0) >= 1
    assert events2.get("/jax/compilation_cache/cache_misses", 0) == 0  # the warm run compiles nothing
    assert second == first  # the same program, the same numbers (every float of the JSON, exactly)
    # --no-cache: the warm caches are neither read nor written
    files = _files(cache_dir)
    third, events3 = _run(scene, cache_dir, "--no-cache")
    assert events3.get("/jax/compilation_cache/cache_hits", 0) == 0
    assert all(events3[f"program_cache/{k}"] == 0 for k in ("hits", "loads", "misses", "writes", "bypassed"))
    assert _files(cache_dir) == files
    assert third["tca"]["te_um"] == pytest.approx(first["tca"]["te_um"], rel=1e-9, abs=1e-9)


# --------------------------------------------------------------------------------------
# The key: computed without tracing, so these are cheap.


def _scene(**kwargs):
    pair = gj.InvoluteGearPair((23, 41), 4.0, 20.0, 12.0, 20.0)
    kwargs.setdefault("accuracy", "fast")
    return gj.Scene(pair, **kwargs)


def _key_of(scene):
    scene = _prepare(scene)
    leaves, treedef = jax.tree_util.tree_flatten(scene)
    return program_cache._entry_key(_simulate, "simulate", treedef, leaves)


@pytest.fixture(scope="module")
def base_key():
    return _key_of(_scene())


def test_key_is_the_same_for_a_rebuilt_scene_of_the_same_structure(base_key):
    pair = gj.InvoluteGearPair((23, 41), 4.0, 20.0, 12.0, 21.0)  # other values, same structure
    assert _key_of(gj.Scene(pair, accuracy="fast")) == base_key


@pytest.mark.parametrize(
    "change",
    ["accuracy", "slices", "dtype", "modification", "torque", "pitches", "teeth", "shape"],
)
def test_key_changes_with_what_traces_differently(base_key, change):
    fast = gj.Accuracy.preset("fast")
    if change == "accuracy":
        scene = _scene(accuracy="default")
    elif change == "slices":
        scene = _scene(accuracy=fast.replace(face_slices=11))
    elif change == "dtype":
        scene = _scene(accuracy=fast.replace(dtype="float32"))
    elif change == "modification":
        scene = _scene(modification=gj.FlankModification(tip_relief=0.008, tip_relief_length=3.0))
    elif change == "torque":
        scene = _scene(operating=gj.OperatingPoint(torque=100e3))
    elif change == "pitches":
        scene = _scene(pitches=2)
    elif change == "teeth":
        scene = gj.Scene(gj.InvoluteGearPair((23, 43), 4.0, 20.0, 12.0, 20.0), accuracy="fast")
    else:  # the same structure with batched leaves
        scene = jax.tree_util.tree_map(lambda x: jnp.stack([x, x]), _scene())
    assert _key_of(scene) != base_key


def test_key_follows_the_gearjax_sources_and_jax_settings(base_key, monkeypatch):
    with monkeypatch.context() as patch:
        patch.setattr(_program_key, "_package_digest", lambda: "edited")
        _program_key._environment.cache_clear()
        assert _key_of(_scene()) != base_key  # an edited source file never loads an old program
    _program_key._environment.cache_clear()
    assert _key_of(_scene()) == base_key
    with jax.numpy_dtype_promotion("standard"):  # the tests run with "strict"
        assert _key_of(_scene()) != base_key
    single = _scene(accuracy=gj.Accuracy.preset("fast").replace(dtype="float32"))
    with jax.enable_x64(False):  # how simulate traces a float32 scene
        key_32 = _key_of(single)
    assert _key_of(single) != key_32


KEY_PROBE = textwrap.dedent(
    """
    import jax
    jax.config.update("jax_enable_x64", True)
    import gearjax as gj
    from gearjax.runtime import program_cache
    from gearjax.pipeline import prepare as _prepare, simulate_program as _simulate
    pair = gj.InvoluteGearPair((23, 41), 4.0, 20.0, 12.0, 20.0)
    scene = _prepare(gj.Scene(pair, operating=gj.OperatingPoint(torque=100e3), effects=("impact",), accuracy="fast"))
    leaves, treedef = jax.tree_util.tree_flatten(scene)
    print(program_cache._entry_key(_simulate, "simulate", treedef, leaves))
    """
)


def test_key_is_the_same_in_processes_with_other_hash_seeds():
    # the effects are a frozenset, whose iteration order follows the string hash seed
    keys = set()
    for seed in ("1", "2"):
        env = dict(os.environ, PYTHONHASHSEED=seed)
        out = subprocess.run([sys.executable, "-c", KEY_PROBE], env=env, capture_output=True, text=True, timeout=300)
        assert out.returncode == 0, out.stderr[-2000:]
        keys.add(out.stdout.strip().splitlines()[-1])
    assert len(keys) == 1


def test_static_values_that_cannot_be_keyed_bypass_the_cache():
    with pytest.raises(_program_key.Uncacheable):
        _program_key.canon(lambda x: x)
    with pytest.raises(_program_key.Uncacheable):
        _program_key.canon(object())
    assert _program_key.canon(frozenset({"ltca", "impact"})) == _program_key.canon(frozenset({"impact", "ltca"}))
    assert _program_key.canon(0.1) != _program_key.canon(math.nextafter(0.1, 1.0))
    assert _program_key.canon((1, 2)) != _program_key.canon([1, 2]) != _program_key.canon((1.0, 2.0))
    assert _program_key.canon(gj.Accuracy.preset("fast")) != _program_key.canon(gj.Accuracy.preset("default"))


def test_calls_under_a_transformation_bypass_the_cache(tmp_path):
    scene = _scene(accuracy=gj.Accuracy.preset("fast").replace(positions_per_pitch=4, face_slices=3))
    before = program_cache.program_cache_info()
    with program_cache.program_cache(path=tmp_path) as directory:
        assert directory == tmp_path
        jax.eval_shape(gj.simulate, scene)  # traced leaves: nothing loaded, nothing stored
    after = program_cache.program_cache_info()
    assert after["bypassed"] == before["bypassed"] + 1
    assert after["misses"] == before["misses"] and after["writes"] == before["writes"]
    assert list(tmp_path.iterdir()) == []
    assert program_cache.program_cache_dir() is None  # the block's setting is gone


def _doubled(tree):
    return {"y": tree["x"] * tree["n"], "label": "doubled"}


def test_an_entry_round_trips_and_an_old_or_corrupt_one_is_a_miss(tmp_path, monkeypatch):
    # a tiny program: the entry holds Exported.serialize()'s bytes, read back with
    # jax.export.deserialize; an entry of another format (1: Exported's private fields)
    # or a corrupt file is traced again and replaced, never an error
    tree = {"x": jnp.arange(3.0), "n": 2}
    monkeypatch.setattr(program_cache, "_programs", {})

    def call():
        program_cache._programs.clear()  # as in a new process: the entry is read from disk
        before = program_cache.program_cache_info()
        out = program_cache.cached_call(_doubled, tree, name="doubled")
        after = program_cache.program_cache_info()
        assert out["label"] == "doubled" and out["y"].tolist() == [0.0, 2.0, 4.0]
        return {k: after[k] - before[k] for k in after}

    miss = {"hits": 0, "loads": 0, "misses": 1, "writes": 1, "bypassed": 0}
    with program_cache.program_cache(path=tmp_path):
        assert call() == miss
        (entry,) = tmp_path.iterdir()
        stored = pickle.loads(entry.read_bytes())
        assert stored["format"] == program_cache.FORMAT and isinstance(stored["exported"], bytes)
        assert call() == {"hits": 1, "loads": 1, "misses": 0, "writes": 0, "bypassed": 0}
        entry.write_bytes(pickle.dumps({**stored, "format": 1, "exported": {"fun_name": "flat_fn"}}))
        assert call() == miss
        entry.write_bytes(b"not a pickle")
        assert call() == miss
        assert call()["hits"] == 1  # replaced by a good entry
    assert [p.name for p in tmp_path.iterdir()] == [entry.name]


def test_the_program_cache_is_off_unless_asked_for():
    import gearjax  # noqa: F401

    assert program_cache.program_cache_dir() is None


def test_the_command_leaves_the_process_settings_as_they_were(tmp_path, capsys):
    from gearjax.cli import main

    path = tmp_path / "bad.toml"
    path.write_text("[pair]\nteeth = [29]\nnormal_module = 5.0\n")
    assert main(["run", str(path)]) == 2  # fails while reading the scene, inside the caches' scope
    threshold = jax.config.jax_persistent_cache_min_compile_time_secs  # JAX's cache stays enabled
    assert threshold > 0.0
    assert main(["run", str(path)]) == 2
    assert program_cache.program_cache_dir() is None  # the command's own settings are gone
    assert jax.config.jax_persistent_cache_min_compile_time_secs == threshold
    capsys.readouterr()


def test_an_excluded_program_is_written_to_the_persistent_cache_only_where_it_loads_safely(tmp_path):
    """`exclude_from_persistent_cache` (gearjax's gradient program, whose cached executable
    crashed the process that loaded it with jaxlib < 0.12): of two programs compiled in a
    fresh process with an empty cache, the plain one is written, and the excluded one only
    where this jaxlib loads such programs safely (there the exclusion does nothing); both run."""
    script = textwrap.dedent(
        """
        import sys
        import jax
        import jax.numpy as jnp
        import gearjax as gj

        jax.config.update("jax_compilation_cache_dir", sys.argv[1])
        jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)

        @jax.jit
        def plain_program(x):
            return jnp.sin(x) * 2.0

        @jax.jit
        def excluded_program(x):
            gj.exclude_from_persistent_cache()
            return jnp.sin(x) * 2.0

        print(float(plain_program(1.0)), float(excluded_program(1.0)))
        """
    )
    env = {k: v for k, v in os.environ.items() if not k.startswith("JAX_")}
    proc = subprocess.run([sys.executable, "-c", script, str(tmp_path)], capture_output=True, text=True, env=env,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    plain, excluded = (float(v) for v in proc.stdout.split())
    assert plain == excluded == pytest.approx(2.0 * math.sin(1.0), rel=1e-6)
    names = [p.name for p in tmp_path.iterdir()]
    assert any(n.startswith("jit_plain_program") for n in names), names
    written = any(n.startswith("jit_excluded_program") for n in names)
    assert written is gradient_cache_safe(), names
