"""A progress line for runs: simulated time, fraction done and speed against real time."""

from __future__ import annotations

import sys
import time


class ProgressBar:
    """Call with (t, q) during a run; prints once the run has taken ``delay`` seconds of wall time.

    On a terminal the line is redrawn in place at most every ``interval`` seconds; elsewhere (a
    log file, CI) a line is printed every 25 % of the run.
    """

    def __init__(
        self, duration: float, stream=None, delay: float = 1.0, interval: float = 0.2, width: int = 30
    ):
        self.duration = duration
        self.stream = stream or sys.stderr
        self.delay, self.interval, self.width = delay, interval, width
        self.start = time.perf_counter()
        self.last_draw = -1.0
        self.last_quarter = 0
        self.shown = False
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())

    def line(self, t: float) -> str:
        """The progress text at simulated time t."""
        wall = time.perf_counter() - self.start
        done = min(max(t / self.duration, 0.0), 1.0) if self.duration > 0 else 1.0
        bar = "#" * int(round(done * self.width))
        speed = t / wall if wall > 0 else 0.0
        return f"[{bar:<{self.width}s}] {t:7.2f} / {self.duration:.2f} s simulated, {speed:5.2f}x real time"

    def __call__(self, t: float, q=None) -> None:
        """Report simulated time t (q is accepted for the simulate() callback signature)."""
        now = time.perf_counter()
        if now - self.start < self.delay:
            return
        if self.tty:
            if now - self.last_draw >= self.interval:
                self.stream.write("\r" + self.line(t))
                self.stream.flush()
                self.last_draw, self.shown = now, True
        else:
            quarter = int(4 * t / self.duration) if self.duration > 0 else 4
            if quarter > self.last_quarter:
                self.last_quarter = quarter
                print(self.line(t), file=self.stream, flush=True)

    def finish(self, t: float) -> None:
        """Draw the final state and end the line (only if anything was shown)."""
        if self.shown:
            self.stream.write("\r" + self.line(t) + "\n")
            self.stream.flush()
