"""Progress display of long runs (optimisation, chunked sweeps): a tqdm bar on a terminal,
plain lines otherwise, or nothing."""

from __future__ import annotations

import sys


class Progress:
    """A tqdm bar (`mode="bar"`), plain lines on standard error (`"lines"`), nothing
    (None), or `"auto"`: a bar when standard error is a terminal, lines otherwise.

    Args:
        mode: "auto", "bar", "lines" or None.
        total: number of steps of the run.
        done: steps already finished (a resumed run).
        label: what a step is ("generation", "chunk"); its first word is the bar's unit.
    """

    def __init__(self, mode: str | None, total: int, done: int, label: str):
        if mode not in ("auto", "bar", "lines", None):
            raise ValueError(f"progress must be 'auto', 'bar', 'lines' or None; got {mode!r}")
        if mode == "auto":
            mode = "bar" if sys.stderr.isatty() else "lines"
        self.mode, self.label, self.total, self.bar = mode, label, total, None
        if mode == "bar":
            from tqdm.auto import tqdm

            self.bar = tqdm(total=total, initial=done, desc=label, unit=label.split()[0], file=sys.stderr)

    def update(self, step: int, elapsed: float, **postfix: str) -> None:
        """Step `step` (1-based) is done, `elapsed` seconds into the run; `postfix` is shown
        beside the bar (e.g. best="8375", points_per_s="120")."""
        if self.mode == "bar":
            self.bar.set_postfix(**postfix, elapsed=f"{elapsed:.0f}s")
            self.bar.update(1)
        elif self.mode == "lines":
            extra = "".join(f"  {k.replace('_', ' ')} {v}" for k, v in postfix.items())
            print(f"{self.label} {step}/{self.total}{extra}  elapsed {elapsed:.1f} s", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
