"""README.md runs top to bottom (issue 15): ``scripts/readme_commands.py`` runs its command blocks in order
in a temporary folder, skipping only the lines marked as needing cameras, MPI-FAUST, an install, many
minutes or a server; the parser, the failure message and the server check are tested on small READMEs."""

from __future__ import annotations

import importlib.util
import os
import re
import socket
import sys
import time
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _script(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, ROOT / "scripts" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # its dataclasses look their module up
    spec.loader.exec_module(mod)
    return mod


rc = _script("readme_commands")

SAMPLE = """```bash
# a comment, not the title
bash scripts/setup.sh
```

# Title

## Use it

```bash
first --a   # plain comment
second \\
   --b x    # needs cameras: a reason
echo "# long" 'and # server'
third       # longest is no marker
# a comment line
fourth      # long
```

```python
print("hi")
```

```text
not a command
```
"""


def test_the_top_of_the_readme_is_kept() -> None:
    lines = (ROOT / "README.md").read_text().splitlines()
    assert lines[:4] == ["```bash", "bash scripts/setup.sh && .venv/bin/bsv demo -o out/demo --overwrite",
                         "bash scripts/test.sh", "```"]


def test_every_picture_the_readme_shows_exists() -> None:
    links = re.findall(r"!\[[^\]]*\]\(([^)\s]+)\)", (ROOT / "README.md").read_text())
    assert "docs/images/segmented-body.png" in links
    for link in links:
        path = ROOT / link
        assert path.is_file() and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", link


def test_blocks_commands_and_markers() -> None:
    setup, todo = rc.readme_commands(SAMPLE)
    assert [c.text for c in setup] == ["bash scripts/setup.sh"]
    assert [(c.first_line.split()[0], c.lang, c.marker) for c in todo] == [
        ("first", "bash", None), ("second", "bash", "needs cameras"), ("echo", "bash", None),
        ("third", "bash", None), ("fourth", "bash", "long"), ('print("hi")', "python", None)]
    second = todo[1]
    assert second.text == "second \\\n   --b x    # needs cameras: a reason" and second.line == 12
    assert all(c.section == "Use it" for c in todo)
    assert rc.trailing_comment("a 'b # c' \"# d\" e\\#f # g") == "g"
    assert rc.trailing_comment("a#b") is None


def test_unrunnable_readmes_are_refused() -> None:
    with pytest.raises(rc.ReadmeError, match="never closed"):
        rc.blocks("# T\n```bash\nls\n")
    with pytest.raises(rc.ReadmeError, match="`cd` would not carry over"):
        rc.readme_commands("# T\n```bash\ncd somewhere\n```\n")
    with pytest.raises(rc.ReadmeError, match="ends in a backslash"):
        rc.readme_commands("# T\n```bash\nls \\\n```\n")


def test_a_failing_command_names_itself_and_its_stderr(tmp_path: Path) -> None:
    (cmd,) = rc.readme_commands("# T\n## S\n```bash\nls ./no-such-file   # why\n```\n")[1]
    with pytest.raises(rc.CommandFailed) as e:
        rc.run_command(cmd, tmp_path, dict(os.environ))
    msg = str(e.value)
    assert "README line 4 (S) failed with exit status 2" in msg and "ls ./no-such-file" in msg
    assert "no-such-file" in msg.split("--- stderr ---")[1]


def test_a_server_is_started_checked_and_stopped(tmp_path: Path) -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    text = f"# T\n```bash\npython -m http.server {port} --bind 127.0.0.1   # server: at http://127.0.0.1:{port}/\n```\n"
    (cmd,) = rc.readme_commands(text)[1]
    assert cmd.marker == "server"
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    assert rc.run_server(cmd, tmp_path, env, start_s=60.0) < 60.0
    time.sleep(0.5)
    with pytest.raises(ConnectionRefusedError):  # stopped: nothing listens any more
        socket.create_connection(("127.0.0.1", port), timeout=5).close()
    (dead,) = rc.readme_commands("# T\n```bash\nfalse   # server: at http://127.0.0.1:9/\n```\n")[1]
    with pytest.raises(rc.CommandFailed, match="exited with status 1 instead of serving"):
        rc.run_server(dead, tmp_path, env, start_s=30.0)


def test_the_commands_before_the_title_run_only_with_setup_and_in_the_repository(tmp_path: Path) -> None:
    readme = tmp_path / "README.md"
    readme.write_text("```bash\necho setup > ran-setup.txt\nbash scripts/test.sh\n```\n\n# Title\n\n"
                      "```bash\necho use > ran-use.txt\n```\n")
    repo, work = tmp_path / "repo", tmp_path / "work"
    repo.mkdir()
    quiet = rc.run(readme, work, repo=repo)
    assert [o.status for o in quiet] == ["skipped", "skipped", "ok"] and not (repo / "ran-setup.txt").exists()
    assert "--setup runs it" in quiet[0].reason and "runs this script" in quiet[1].reason
    assert (work / "ran-use.txt").read_text() == "use\n" and (work / "examples").is_symlink()
    again = rc.run(readme, tmp_path / "work2", setup=True, repo=repo)
    assert [o.status for o in again] == ["ok", "skipped", "ok"]
    assert (repo / "ran-setup.txt").read_text() == "setup\n" and not (tmp_path / "work2" / "ran-setup.txt").exists()


@pytest.mark.slow
def test_the_readme_commands_run_in_order(tmp_path: Path) -> None:
    readme = tmp_path / "README.md"  # this test's copy: an edit while it runs does not change what it checks
    readme.write_text((ROOT / "README.md").read_text())
    t0 = time.monotonic()
    outcomes = rc.run(readme, tmp_path / "work", report=rc.print_outcome)
    seconds = time.monotonic() - t0
    ran = [o for o in outcomes if o.status == "ok"]
    skipped = [o for o in outcomes if o.status == "skipped"]
    print(f"{len(ran)} commands ran, {len(skipped)} skipped, in {seconds:.1f} s")
    setup, todo = rc.readme_commands(readme.read_text())
    # everything after the title ran unless its line carries a marker the runner knows
    assert {o.command for o in skipped} == set(setup) | {c for c in todo if c.marker is not None}
    assert all(rc.MARKERS[c.marker][0] in ("skip", "long", "server") for c in todo if c.marker)
    assert len(ran) >= 12
    assert {o.command.lang for o in ran} == {"bash", "python"}
    # the lab path really used the calibration that `bsv calibrate` wrote from examples/calib
    work = tmp_path / "work"
    assert (work / "calibration.json").is_file() and (work / "out" / "capture" / "report.html").is_file()
    # the README's picture is drawn from such a folder: its script still works on the demo's outputs
    fig = _script("make_readme_figure").draw(work / "out" / "demo-plain")
    fig.savefig(tmp_path / "figure.png")
    assert (tmp_path / "figure.png").stat().st_size > 20_000
