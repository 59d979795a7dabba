"""A progress line for long runs: on a terminal's stderr, one line redrawn in place with a bar, the rate and the time
left; nothing at all when stderr is not a terminal, so CI logs hold only the results."""

from __future__ import annotations

import sys
import time
from typing import TextIO

BAR_WIDTH = 24
REDRAW_SECONDS = 0.2


class ProgressLine:
    """Draws `what: [#####.....] done/total unit, rate, ~time left (note)` once `delay` seconds have passed (a short
    run shows nothing); `close` ends the line."""

    def __init__(self, what: str, unit: str, stream: TextIO | None = None, delay: float = 1.0):
        self.what, self.unit = what, unit
        self.stream = stream if stream is not None else sys.stderr
        self.delay = delay
        self.start = time.perf_counter()
        self.drawn_at = 0.0
        self.width = 0
        self.live = _is_terminal(self.stream)

    def update(self, done: int, total: int, note: str = "") -> None:
        if not self.live:
            return
        now = time.perf_counter()
        elapsed = now - self.start
        if elapsed < self.delay or (now - self.drawn_at < REDRAW_SECONDS and done < total):
            return
        self.drawn_at = now
        text = f"{self.what}: {render_bar(done, total)} {done}/{total} {self.unit}"
        if done and elapsed > 0:
            text += f", {done / elapsed:.0f}/s, ~{format_seconds(elapsed * (total - done) / done)} left"
        if note:
            text += f" ({note})"
        self.stream.write("\r" + text.ljust(self.width))
        self.stream.flush()
        self.width = len(text)

    def close(self) -> None:
        if self.live and self.width:
            self.stream.write("\r" + " " * self.width + "\r")
            self.stream.flush()
            self.width = 0


def render_bar(done: int, total: int, width: int = BAR_WIDTH) -> str:
    filled = min(width, width * done // total) if total > 0 else 0
    return "[" + "#" * filled + "." * (width - filled) + "]"


def format_seconds(seconds: float) -> str:
    seconds = int(round(seconds))
    if seconds < 60:
        return f"{seconds} s"
    minutes, seconds = divmod(seconds, 60)
    if minutes < 60:
        return f"{minutes} min {seconds:02d} s"
    hours, minutes = divmod(minutes, 60)
    return f"{hours} h {minutes:02d} min"


def _is_terminal(stream: TextIO) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False
