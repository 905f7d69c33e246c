"""The process settings that gearjax makes on import (see `gearjax.runtime.versions`)."""

import os
import subprocess
import sys
import textwrap
import warnings

import pytest
from jaxlib import version as jaxlib_version

import gearjax  # noqa: F401  (import sets them)
from gearjax.runtime import versions as _runtime


def test_flags_set_on_import_only_for_an_affected_jaxlib():
    flags = os.environ.get("XLA_FLAGS", "")
    assert (f"--{_runtime.FLAG}=false" in flags) is _runtime.affected(jaxlib_version.__version__)


@pytest.mark.parametrize(("version", "expected"), [
    ("0.10.2", ["PJRT_NPROC=1", f"--{_runtime.FLAG}=false", f"--{_runtime.COMPILER_FLAG}=false"]),
    ("0.11.0", ["PJRT_NPROC=1", f"--{_runtime.FLAG}=false"]),
    ("0.11.1", []), ("0.12.0.1", []),
])
def test_a_current_jaxlib_gets_no_setting(monkeypatch, version, expected):
    for name in (*_runtime.NPROC_VARIABLES, "XLA_FLAGS"):
        monkeypatch.setenv(name, "")  # recorded, so that what `configure` sets is undone
        monkeypatch.delenv(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # backends may already run here
        assert _runtime.configure(version) == expected
    assert ("PJRT_NPROC" in os.environ) is bool(expected)
    assert ("XLA_FLAGS" in os.environ) is bool(expected)


@pytest.mark.parametrize(("version", "expected"), [
    ("0.10.2", False), ("0.11.2", False), ("0.12.0", True), ("0.12.0.1", True), ("1.0.0", True), ("nightly", False),
])
def test_gradient_cache_safe_versions(version, expected):
    assert _runtime.gradient_cache_safe(version) is expected


def test_user_choice_respected(monkeypatch):
    monkeypatch.setenv("XLA_FLAGS", f"--{_runtime.FLAG}=true --xla_foo=1")
    assert _runtime.configure_xla_flags("0.10.2") is False
    assert os.environ["XLA_FLAGS"] == f"--{_runtime.FLAG}=true --xla_foo=1"


def test_flag_appended_to_existing(monkeypatch):
    monkeypatch.setenv("XLA_FLAGS", "--xla_foo=1")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # backends may already run here
        assert _runtime.configure_xla_flags("0.10.2") is True
    assert os.environ["XLA_FLAGS"] == f"--xla_foo=1 --{_runtime.FLAG}=false"


@pytest.mark.parametrize(("version", "expected"), [
    ("0.9.2", False), ("0.10.0", True), ("0.10.2", True), ("0.11.0", True), ("0.11.1", False),
    ("0.11.1.dev20260801", False), ("0.10.3rc1", True), ("1.0.0", False),
])
def test_affected_jaxlib_versions(version, expected):
    assert _runtime.affected(version) is expected


def test_compiler_flag_set_on_import_for_the_measured_jaxlib():
    expected = _runtime._in_range(jaxlib_version.__version__, _runtime.COMPILER_JAXLIB, unknown=False)
    assert (f"--{_runtime.COMPILER_FLAG}=false" in os.environ.get("XLA_FLAGS", "")) is expected


@pytest.mark.parametrize(("version", "expected"), [
    ("0.9.2", False), ("0.10.0", True), ("0.10.2", True), ("0.10.9rc1", True), ("0.11.0", False),
    ("1.0.0", False), ("nightly", False),
])
def test_compiler_flag_only_for_the_measured_jaxlib_versions(monkeypatch, version, expected):
    """An XLA flag that a jaxlib does not know aborts the process: unknown versions and
    version strings get none."""
    monkeypatch.setenv("XLA_FLAGS", "--xla_foo=1")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # backends may already run here
        assert _runtime.configure_compiler(version) is expected
    assert os.environ["XLA_FLAGS"] == "--xla_foo=1" + (f" --{_runtime.COMPILER_FLAG}=false" if expected else "")


def test_compiler_flag_user_choice_respected(monkeypatch):
    monkeypatch.setenv("XLA_FLAGS", f"--{_runtime.COMPILER_FLAG}=true")
    assert _runtime.configure_compiler("0.10.2") is False
    assert os.environ["XLA_FLAGS"] == f"--{_runtime.COMPILER_FLAG}=true"


def test_thread_pool_setting(monkeypatch):
    for name in _runtime.NPROC_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        assert _runtime.configure_thread_pool("0.9.2") is False
        assert "PJRT_NPROC" not in os.environ
        assert _runtime.configure_thread_pool("0.10.2") is True
        assert os.environ["PJRT_NPROC"] == "1"
        monkeypatch.setenv("PJRT_NPROC", "4")  # the user's choice stays
        assert _runtime.configure_thread_pool("0.10.2") is False
        assert os.environ["PJRT_NPROC"] == "4"
        monkeypatch.delenv("PJRT_NPROC")
        monkeypatch.setenv("NPROC", "2")
        assert _runtime.configure_thread_pool("0.10.2") is False
        assert "PJRT_NPROC" not in os.environ


# Two independent batched LU solves in one program, each above jaxlib's 2e5-flop threshold
# for splitting its batch over XLA's pool. With jaxlib 0.10.2 on 2 cores and the concurrency-
# optimised scheduler on, this program never returns once both calls run at once (5 of 5
# tries hung without `PJRT_NPROC=1`, 0 of 5 with it; docs/decisions/0001-jaxlib-workarounds.md).
DEADLOCK = textwrap.dedent("""
    import gearjax, jax, jax.numpy as jnp
    jax.config.update("jax_enable_x64", True)
    k = jax.random.split(jax.random.PRNGKey(0), 4)
    A1, A2 = (jax.random.normal(key, (4000, 10, 10)) + 5 * jnp.eye(10) for key in k[:2])
    b1, b2 = (jax.random.normal(key, (4000, 10, 1)) for key in k[2:])
    f = jax.jit(lambda A1, A2, b1, b2: (jnp.linalg.solve(A1, b1), jnp.linalg.solve(A2, b2)))
    for i in range(20):
        jax.block_until_ready(f(A1 + i * 1e-9, A2, b1, b2))
    print("returned")
""")


def test_batched_lapack_calls_side_by_side_return():
    """The program above returns: with an affected jaxlib under gearjax's `PJRT_NPROC=1`
    alone (the scheduler flag turned back on; it hangs without it on 2 cores), with a
    current one with no setting at all."""
    env = {k: v for k, v in os.environ.items() if k not in _runtime.NPROC_VARIABLES}
    env["XLA_FLAGS"] = f"--{_runtime.FLAG}=true" if _runtime.affected(jaxlib_version.__version__) else ""
    run = subprocess.run([sys.executable, "-c", DEADLOCK], env=env, capture_output=True, text=True, timeout=180)
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.strip() == "returned"
