"""The reporter ``Scene.run(progress=True)`` uses: a tqdm bar over a transient's time steps
when tqdm is installed, else one line per stage (and a step counter) on ``sys.stderr``."""

import sys

try:
    from tqdm.auto import tqdm
except ImportError:  # tqdm is optional
    tqdm = None


class Reporter:
    """Called as ``reporter(stage, done, total)``; ``close()`` ends its bar."""

    def __init__(self):
        self._bar = None

    def __call__(self, stage: str, done: int, total: int) -> None:
        if total > 0 and tqdm is not None:
            if self._bar is None:
                self._bar = tqdm(total=total, desc="demcon: solve", unit="step")
            self._bar.update(done - self._bar.n)
        elif total > 0:
            sys.stderr.write(f"\rdemcon: {stage} {done}/{total} steps")
            sys.stderr.flush()
        else:
            sys.stderr.write(f"demcon: {stage}\n")
            sys.stderr.flush()

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None
