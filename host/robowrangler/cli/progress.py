"""Progress on stderr while a command works (record, proxy, home, loop, grasp): a live line on a terminal,
else a line every PROGRESS_PERIOD_S (logs and pipes get a readable trace, not a flood)."""

from __future__ import annotations

from robowrangler.cli.context import CliContext

PROGRESS_PERIOD_S = 2.0  # a progress line on stderr this often when stderr is not a terminal
LIVE_PERIOD_S = 0.25  # the live line's refresh on a terminal


class Progress:
    """Progress on stderr: a live line on a terminal, else a line every PROGRESS_PERIOD_S."""

    def __init__(self, ctx: CliContext) -> None:
        self.ctx = ctx
        self.tty = bool(getattr(ctx.env.stderr, "isatty", lambda: False)())
        self.last_s = -1e9
        self.live = False

    def show(self, text: str, now_s: float) -> None:
        period_s = LIVE_PERIOD_S if self.tty else PROGRESS_PERIOD_S
        if now_s - self.last_s < period_s:
            return
        self.last_s = now_s
        if self.tty:
            self.ctx.env.stderr.write(f"\rwrangler: {text}\033[K")
            self.ctx.env.stderr.flush()
            self.live = True
        else:
            self.ctx.note(text)

    def note(self, text: str) -> None:
        self.end_line()
        self.ctx.note(text)

    def end_line(self) -> None:
        if self.live:
            self.ctx.env.stderr.write("\n")
            self.ctx.env.stderr.flush()
            self.live = False
