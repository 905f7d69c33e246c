"""The run directory of a long run (an optimisation, `gearjax.optimize.run`; a chunked
sweep, `gearjax.sweep.run`): a description checked on resume, the history appended and
synced per step, and the state replaced atomically."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np


class RunDirectoryError(ValueError):
    """The run directory holds another run, or one that cannot be resumed."""


#: marks a key that one of two descriptions lacks (`_differences`)
_ABSENT = object()


def _differences(saved: dict, now: dict, prefix: str = "") -> list[str]:
    """The keys whose values differ, nested dicts followed (`config.smoothing`); a key
    absent from the saved run (written by another version) says so."""
    out = []
    for key in sorted(set(saved) | set(now)):
        a, b = saved.get(key, _ABSENT), now.get(key, _ABSENT)
        if a == b:
            continue
        if isinstance(a, dict) and isinstance(b, dict):
            out += _differences(a, b, f"{prefix}{key}.")
        else:
            out.append(f"{prefix}{key}" + (" (absent from the saved run: written by another version of gearjax)"
                                           if a is _ABSENT else ""))
    return out


class RunDirectory:
    """The files of one run (see the module docstring)."""

    def __init__(self, path: str | os.PathLike, description: dict, resume: bool):
        self.path = Path(path)
        self.description = description
        self.path.mkdir(parents=True, exist_ok=True)
        existing = self.path / "run.json"
        if existing.exists():
            if not resume:
                raise RunDirectoryError(
                    f"run directory {self.path} already holds a run: pass resume=True (--resume) "
                    "to continue it, or choose another directory"
                )
            saved, now = json.loads(existing.read_text()), json.loads(json.dumps(description))
            if saved != now:
                raise RunDirectoryError(f"cannot resume {self.path}: the run differs in {', '.join(_differences(saved, now))}")
        else:
            atomic_write(existing, json.dumps(description, indent=2).encode())

    @property
    def history_path(self) -> Path:
        return self.path / "history.jsonl"

    def load(self, template) -> tuple[Any, list[dict]] | None:
        """The saved state (same structure as `template`) and the history up to it, or None."""
        state_file = self.path / "state.npz"
        if not state_file.exists():
            return None
        with np.load(state_file) as data:
            leaves, treedef = jax.tree_util.tree_flatten(template)
            restored = [jnp.asarray(data[f"leaf_{i}"], dtype=jnp.asarray(leaf).dtype) for i, leaf in enumerate(leaves)]
            step = int(data["step"])
        records = []
        if self.history_path.exists():
            for line in self.history_path.read_text().splitlines():
                try:
                    record = json.loads(line)
                except json.JSONDecodeError:
                    break  # a line cut by a kill
                if record["step"] > step:
                    break
                records.append(record)
        if len(records) != step:
            raise RunDirectoryError(f"cannot resume {self.path}: history has {len(records)} finished steps, state has {step}")
        atomic_write(self.history_path, "".join(json.dumps(r) + "\n" for r in records).encode())
        return jax.tree_util.tree_unflatten(treedef, restored), records

    def save(self, state, record: dict) -> None:
        """Append the step's record, then replace the state (the order resume relies on)."""
        with open(self.history_path, "a") as f:
            f.write(json.dumps(record) + "\n")
            f.flush()
            os.fsync(f.fileno())
        arrays = {f"leaf_{i}": np.asarray(leaf) for i, leaf in enumerate(jax.tree_util.tree_leaves(state))}
        arrays["step"] = np.asarray(record["step"])
        tmp = self.path / "state.tmp.npz"
        with open(tmp, "wb") as f:
            np.savez(f, **arrays)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, self.path / "state.npz")


def atomic_write(path: Path, data: bytes) -> None:
    """Write `data` to `path` through a synced temporary file and `os.replace`."""
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)
