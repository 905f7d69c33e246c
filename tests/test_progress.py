"""What long runs and compilations tell the user (`gearjax.io.progress`)."""

import json
import os
import subprocess
import sys
import textwrap
import time

import jax
import jax.numpy as jnp
import pytest

from gearjax.io.progress import Progress, compiling


def test_a_slow_block_says_what_it_compiles_and_how_long_it_took(capsys):
    program = jax.jit(lambda x: jnp.sin(x) * 1.2345678)  # a program no other test compiles
    with compiling("the test program", mode="lines", delay=0.0) as stats:
        jax.block_until_ready(program(jnp.arange(3.0)))
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines[0].startswith("gearjax: compiling the test program (")
    assert lines[-1].startswith("gearjax: the test program ready in ")
    assert stats["elapsed_s"] >= stats["compile_s"] > 0.0


@pytest.mark.parametrize("mode", ["lines", "bar"])
def test_a_block_stopped_by_an_error_says_so_not_ready(capsys, mode):
    with pytest.raises(ZeroDivisionError), compiling("the failing program", mode=mode, delay=0.0):
        time.sleep(0.05)  # let the notice appear
        1 / 0
    err = capsys.readouterr().err
    assert "stopped by an error after" in err and "ready in" not in err


@pytest.mark.parametrize("mode", ["lines", "bar", None])
def test_a_quick_block_or_no_display_prints_nothing(capsys, mode):
    with compiling("nothing", mode=mode, delay=0.0 if mode is None else 60.0) as stats:
        pass
    assert capsys.readouterr().err == ""
    assert stats["elapsed_s"] < 60.0


def test_the_bar_appears_with_the_first_finished_step(capsys):
    bar = Progress("bar", total=3, done=0, label="generation")
    assert bar.bar is None  # no bar at 0 % while the first step compiles
    bar.update(1, 1.0, best="1")
    assert bar.bar is not None and bar.bar.n == 1
    bar.close()
    capsys.readouterr()


CHILD = textwrap.dedent("""
    import json, sys
    import jax, jax.numpy as jnp
    from gearjax.io.progress import compiling
    jax.config.update("jax_compilation_cache_dir", sys.argv[1])
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    f = jax.jit(lambda x: jnp.cumsum(jnp.cos(x) ** 3) * 7.654321)
    with compiling("the cached program", mode="lines", delay=0.0) as stats:
        jax.block_until_ready(f(jnp.arange(5.0)))
    print(json.dumps(stats))
""")


def test_a_second_process_reports_the_program_loaded_from_the_cache(tmp_path):
    env = {k: v for k, v in os.environ.items() if not k.startswith("JAX_")}
    runs = [subprocess.run([sys.executable, "-c", CHILD, str(tmp_path)], capture_output=True, text=True, env=env,
                           timeout=120) for _ in range(2)]
    for run in runs:
        assert run.returncode == 0, run.stderr[-2000:]
    first, second = (json.loads(run.stdout.strip().splitlines()[-1]) for run in runs)
    assert first["loaded"] == 0 and first["compile_s"] > 0.0
    assert second["loaded"] >= 1
    assert f"cached in {tmp_path}" in runs[1].stderr.splitlines()[0]
    assert "loaded from the cache" in runs[1].stderr.splitlines()[-1]
