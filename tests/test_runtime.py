"""The XLA CPU flag that gearjax sets on import (see `gearjax._runtime`)."""

import os
import warnings

import gearjax  # noqa: F401  (import sets the flag)
from gearjax import _runtime


def test_flag_set_on_import():
    assert f"--{_runtime.FLAG}=false" in os.environ["XLA_FLAGS"]


def test_user_choice_respected(monkeypatch):
    monkeypatch.setenv("XLA_FLAGS", f"--{_runtime.FLAG}=true --xla_foo=1")
    assert _runtime.configure_xla_flags() is False
    assert os.environ["XLA_FLAGS"] == f"--{_runtime.FLAG}=true --xla_foo=1"


def test_flag_appended_to_existing(monkeypatch):
    monkeypatch.setenv("XLA_FLAGS", "--xla_foo=1")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # backends may already run here
        assert _runtime.configure_xla_flags() is True
    assert os.environ["XLA_FLAGS"] == f"--xla_foo=1 --{_runtime.FLAG}=false"
