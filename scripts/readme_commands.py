#!/usr/bin/env python3
"""Runs the README's command blocks in order, as a new user would, in a temporary folder.

Every ```bash block is split into commands (a line ending in a backslash continues on the next), and each
command runs in its own ``bash -o pipefail -c`` in the work folder; every ```python block runs as one
program. The work folder is a fresh temporary directory holding a link to the repository's ``examples/``
(the commands' inputs, as in a clone's root); PATH starts with the repository's ``.venv/bin`` (``bsv``,
``python``) and the folder of the built ``bsv-cli``. The first failing command stops the run with its
README line, exit status and the end of its stderr and stdout.

A command is skipped only when its README line says so, with a trailing comment that starts with a marker
(``# needs cameras: 5 s still capture``); the markers and what they mean are :data:`MARKERS`. ``--long``
also runs the ``long`` ones and starts each ``server`` one, waits until it answers (or stays up), and
stops it. The commands before the README's title (setup + demo, and the tests) are what made this
environment, so by default they are reported, not run; ``--setup`` runs them first, in the repository's
folder where they belong (``bash scripts/setup.sh`` is idempotent), except ``bash scripts/test.sh``, which
runs this very script through tests/python/test_readme_commands.py.

Usage: python scripts/readme_commands.py [--setup] [--long] [--keep] [--workdir DIR] [--readme README.md]
Exit status 0 when every command that ran succeeded, 1 on a failure, 2 on a README the runner cannot read.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Marker (start of a line's trailing comment) -> (what the runner does, why). "skip": never run;
#: "long": run only with --long; "server": with --long, started, checked to answer, then stopped.
MARKERS: dict[str, tuple[str, str]] = {
    "needs cameras": ("skip", "needs two RealSense cameras connected"),
    "needs MPI-FAUST": ("skip", "needs a local copy of the MPI-FAUST data set (never bundled: its licence)"),
    "installs": ("skip", ("installs the package into the environment, which scripts/setup.sh already did "
                         "(the wheel's install is tests/python/test_install.py)")),
    "long": ("long", "runs for minutes; `python scripts/readme_commands.py --long` runs it"),
    "server": ("server", ("serves until stopped; `python scripts/readme_commands.py --long` starts it, checks that "
                         "it answers and stops it")),
}

#: Seconds a command may run before the run fails (a server: seconds to start answering).
TIMEOUT_S = 900.0
SERVER_START_S = 120.0


class ReadmeError(Exception):
    """The README cannot be run as written (a block the runner cannot parse, a shell-state command)."""


class CommandFailed(Exception):
    """A README command exited with a non-zero status (the message has the command and its stderr)."""


@dataclass(frozen=True)
class Command:
    """One command of the README: its text (continuation lines kept), the language of its block, the
    README line it starts on, the heading it stands under, and its marker (None: it runs)."""

    text: str
    lang: str
    line: int
    section: str
    marker: str | None = None

    @property
    def first_line(self) -> str:
        """The command's first line, for reports."""
        return self.text.splitlines()[0].strip()


@dataclass(frozen=True)
class Outcome:
    """What happened to one command: "ok", "skipped" (with the reason) and the seconds it took."""

    command: Command
    status: str
    seconds: float = 0.0
    reason: str = ""


def trailing_comment(line: str) -> str | None:
    """The text after the first ``#`` that starts a shell comment on ``line`` (outside quotes, at the start
    or after whitespace), without the ``#``; None when there is none."""
    quote: str | None = None
    escaped = False
    for i, ch in enumerate(line):
        if escaped:
            escaped = False
        elif ch == "\\" and quote != "'":
            escaped = True
        elif quote is not None:
            if ch == quote:
                quote = None
        elif ch in "'\"":
            quote = ch
        elif ch == "#" and (i == 0 or line[i - 1].isspace()):
            return line[i + 1:].strip()
    return None


def marker_of(comment: str | None) -> str | None:
    """The marker a trailing comment starts with (``needs cameras``, ``long: ...``), or None. A marker
    must be followed by the end of the comment, ``:``, ``;``, ``,`` or a space, so ``longest`` is none."""
    if not comment:
        return None
    for m in MARKERS:
        if comment == m or (comment.startswith(m) and comment[len(m)] in ":;, "):
            return m
    return None


@dataclass(frozen=True)
class Block:
    """A fenced code block: its language, the README line of its first content line, its lines, the
    heading above it ("" before the first heading) and whether it comes before the title (``# ...``)."""

    lang: str
    line: int
    lines: tuple[str, ...]
    section: str
    before_title: bool = False


FENCE = re.compile(r"^(```+|~~~+)\s*([\w+-]*)\s*$")


def blocks(text: str) -> list[Block]:
    """Every fenced code block of a Markdown text, in order (an unclosed fence is a :class:`ReadmeError`)."""
    out: list[Block] = []
    section = ""
    titled = False
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if m is None:
            if lines[i].startswith("#"):
                section = lines[i].lstrip("#").strip()
                titled = titled or lines[i].startswith("# ")
            i += 1
            continue
        fence, lang = m.group(1), m.group(2).lower()
        j = i + 1
        while j < len(lines) and not lines[j].startswith(fence):
            j += 1
        if j == len(lines):
            raise ReadmeError(f"README line {i + 1}: the ``` block is never closed")
        out.append(Block(lang, i + 2, tuple(lines[i + 1:j]), section, not titled))
        i = j + 1
    return out


def commands(block: Block) -> list[Command]:
    """The commands of a block: one per logical line of a shell block (a trailing backslash continues it;
    blank and comment-only lines are skipped), the whole block for a python block; [] for other languages."""
    if block.lang == "python":
        return [Command("\n".join(block.lines), "python", block.line, block.section)]
    if block.lang not in ("bash", "sh", "shell", "console"):
        return []
    out: list[Command] = []
    cur: list[str] = []
    start = 0
    for k, raw in enumerate(block.lines):
        if not cur:
            if not raw.strip() or raw.lstrip().startswith("#"):
                continue
            start = block.line + k
        cur.append(raw)
        if raw.rstrip().endswith("\\"):
            continue
        text = "\n".join(cur)
        word = cur[0].split()[0]
        if word in ("cd", "export", "source", ".", "pushd", "popd"):
            raise ReadmeError(f"README line {start}: `{word}` would not carry over: the runner runs each command "
                              "in its own shell in one folder; write the paths into the commands instead")
        out.append(Command(text, "bash", start, block.section, marker_of(trailing_comment(cur[-1]))))
        cur = []
    if cur:
        raise ReadmeError(f"README line {start}: the command ends in a backslash at the end of its block")
    return out


def readme_commands(text: str) -> tuple[list[Command], list[Command]]:
    """(setup commands: those of the blocks before the README's title, the commands to run in order)."""
    setup: list[Command] = []
    run: list[Command] = []
    for b in blocks(text):
        (setup if b.before_title else run).extend(commands(b))
    return setup, run


def find_cli() -> Path:
    """The built ``bsv-cli``: $BSV_CLI, else the newest of the debug and release builds in
    $CARGO_TARGET_DIR and ./target (scripts/setup.sh builds target/debug/bsv-cli)."""
    env = os.environ.get("BSV_CLI")
    if env:
        p = Path(env)
        if not (p.is_file() and os.access(p, os.X_OK)):
            raise ReadmeError(f"BSV_CLI={env} is not an executable file")
        return p
    dirs = [Path(d) for d in (os.environ.get("CARGO_TARGET_DIR"), str(ROOT / "target")) if d]
    found = [d / prof / "bsv-cli" for d in dirs for prof in ("debug", "release")]
    found = [p for p in found if p.is_file() and os.access(p, os.X_OK)]
    if not found:
        raise ReadmeError("no built bsv-cli (looked in $CARGO_TARGET_DIR and target/, debug and release): run "
                          "`bash scripts/setup.sh` (it runs `cargo build -p bsv-cli`) or set BSV_CLI")
    return max(found, key=lambda p: p.stat().st_mtime)


def environment(cli: Path) -> dict[str, str]:
    """The commands' environment: this one with the venv's bin and bsv-cli's folder first on PATH, a
    non-interactive matplotlib backend and no standard input (set when running)."""
    venv = ROOT / ".venv"
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([str(venv / "bin"), str(cli.parent), env.get("PATH", "")])
    env["VIRTUAL_ENV"] = str(venv)
    env["MPLBACKEND"] = "Agg"
    env.pop("PYTHONHOME", None)
    return env


def _tail(s: str, n: int = 3000) -> str:
    s = s.strip()
    return s if len(s) <= n else "... " + s[-n:]


def _failed(c: Command, how: str, stdout: str, stderr: str) -> CommandFailed:
    return CommandFailed(f"README line {c.line} ({c.section}) {how}:\n  {c.text}\n--- stderr ---\n{_tail(stderr)}"
                         f"\n--- stdout ---\n{_tail(stdout, 1500)}")


def _argv(c: Command, env: dict[str, str]) -> list[str]:
    if c.lang == "python":
        python = shutil.which("python", path=env["PATH"]) or sys.executable
        return [python, "-c", c.text]
    return ["bash", "-o", "pipefail", "-c", c.text]


def run_command(c: Command, work: Path, env: dict[str, str], timeout: float = TIMEOUT_S) -> float:
    """Runs one command in ``work``; returns its seconds or raises :class:`CommandFailed`."""
    t0 = time.monotonic()
    try:
        p = subprocess.run(_argv(c, env), cwd=work, env=env, stdin=subprocess.DEVNULL, capture_output=True,
                           text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired as e:
        out = e.stdout.decode(errors="replace") if isinstance(e.stdout, bytes) else (e.stdout or "")
        err = e.stderr.decode(errors="replace") if isinstance(e.stderr, bytes) else (e.stderr or "")
        raise _failed(c, f"did not finish in {timeout:g} s", out, err) from None
    if p.returncode != 0:
        raise _failed(c, f"failed with exit status {p.returncode}", p.stdout, p.stderr)
    return time.monotonic() - t0


def run_server(c: Command, work: Path, env: dict[str, str], start_s: float = SERVER_START_S) -> float:
    """Starts a server command in ``work``, waits until the first http:// address in its comment answers
    (or, without one, until it has stayed up ``start_s`` / 4 s), then stops its process group."""
    url = re.search(r"https?://[\w.:-]+", trailing_comment(c.text.splitlines()[-1]) or "")
    t0 = time.monotonic()
    log_out = work / f".server-{c.line}.out"
    log_err = work / f".server-{c.line}.err"
    with log_out.open("w") as fo, log_err.open("w") as fe:
        p = subprocess.Popen(_argv(c, env), cwd=work, env=env, stdin=subprocess.DEVNULL, stdout=fo, stderr=fe,
                             start_new_session=True)
    try:
        deadline = t0 + (start_s if url else start_s / 4)
        while time.monotonic() < deadline:
            if p.poll() is not None:
                raise _failed(c, f"exited with status {p.returncode} instead of serving", log_out.read_text(),
                              log_err.read_text())
            if url:
                try:
                    with urllib.request.urlopen(url.group(0), timeout=5):
                        return time.monotonic() - t0
                except urllib.error.HTTPError:
                    return time.monotonic() - t0  # it answered (a login page, a 404): it serves
                except (urllib.error.URLError, OSError):
                    pass
            time.sleep(1.0)
        if url:
            raise _failed(c, f"did not answer at {url.group(0)} within {start_s:g} s", log_out.read_text(),
                          log_err.read_text())
        return time.monotonic() - t0
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGTERM)
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()


def prepare(work: Path) -> None:
    """Makes ``work`` look like a clone's root for the commands' inputs: a link to ``examples/``."""
    work.mkdir(parents=True, exist_ok=True)
    link = work / "examples"
    if not link.exists():
        link.symlink_to(ROOT / "examples", target_is_directory=True)


#: A command before the title that is never run: it runs this script.
RUNS_THIS = "scripts/test.sh"


def run(readme: Path, work: Path, *, long: bool = False, setup: bool = False, repo: Path = ROOT,
        timeout: float = TIMEOUT_S, report: Callable[[Outcome], None] | None = None) -> list[Outcome]:
    """Runs the README's commands in order in ``work`` (see the module docstring); returns what happened
    to each one (the commands before the title first: skipped, or with ``setup`` run in ``repo``), or raises
    :class:`CommandFailed` / :class:`ReadmeError`."""
    before, todo = readme_commands(readme.read_text())
    outcomes: list[Outcome] = []

    def note(o: Outcome) -> None:
        outcomes.append(o)
        if report is not None:
            report(o)

    for c in before:
        if RUNS_THIS in c.text:
            note(Outcome(c, "skipped", reason=f"before the title; {RUNS_THIS} runs this script"))
        elif setup:
            note(Outcome(c, "ok", run_command(c, repo, dict(os.environ), timeout)))
        else:
            note(Outcome(c, "skipped", reason="before the title: the setup that made this environment (--setup runs "
                                              "it in the repository's folder)"))
    env = environment(find_cli())  # after the setup, which builds bsv-cli
    prepare(work)
    for c in todo:
        kind, why = MARKERS[c.marker] if c.marker else ("run", "")
        if kind == "skip" or (kind in ("long", "server") and not long):
            note(Outcome(c, "skipped", reason=f"marked `# {c.marker}`: {why}"))
        elif kind == "server":
            note(Outcome(c, "ok", run_server(c, work, env)))
        else:
            note(Outcome(c, "ok", run_command(c, work, env, timeout)))
    return outcomes


def print_outcome(o: Outcome) -> None:
    """One line per command: status, seconds, README line and the command (skips: the reason)."""
    c = o.command
    head = f"[{o.status:7s} {o.seconds:6.1f} s] README.md:{c.line:<4d} {c.first_line}"
    print(head if o.status != "skipped" else f"{head}\n{'':30s}({o.reason})", flush=True)


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: see the module docstring."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--readme", type=Path, default=ROOT / "README.md")
    ap.add_argument("--long", action="store_true", help="also the commands marked `# long` and `# server`")
    ap.add_argument("--setup", action="store_true",
                    help="first run the commands before the title (setup + demo) in the repository's folder")
    ap.add_argument("--workdir", type=Path, help="run here (default: a new temporary folder)")
    ap.add_argument("--keep", action="store_true", help="keep the temporary folder")
    ap.add_argument("--timeout", type=float, default=TIMEOUT_S, help="seconds one command may run")
    a = ap.parse_args(argv)
    work = a.workdir or Path(tempfile.mkdtemp(prefix="bsv-readme-"))
    print(f"running {a.readme} in {work}", flush=True)
    t0 = time.monotonic()
    try:
        outcomes = run(a.readme, work, long=a.long, setup=a.setup, timeout=a.timeout, report=print_outcome)
    except ReadmeError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except CommandFailed as e:
        print(f"FAILED: {e}\n(outputs kept in {work})", file=sys.stderr)
        return 1
    ran = sum(o.status == "ok" for o in outcomes)
    print(f"{ran} commands ran, {len(outcomes) - ran} skipped, in {time.monotonic() - t0:.1f} s")
    if a.workdir is None and not a.keep:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
