"""Runs every code block of README.md and docs/**/*.md as a reader would paste it.

- ```python blocks run as scripts with this interpreter (the CI venv, built by the README's
  own `pip install` line);
- ```sh / ```bash blocks run line by line in bash, with the built `meid` first on PATH;
- blocks of one file run in order in one fresh working directory holding `examples/` (a link
  to the repository's), so a block may use what an earlier block of the same page wrote.

A block that cannot run here says why in an HTML comment on the line before its fence:
`<!-- snippet: not run (REASON) -->` (e.g. it needs a Slurm cluster, or it is the CI's own
build and test command). ```text, ```toml and unlabelled blocks are shown, not run.

Usage: python .ci/snippets.py [FILE.md ...]   (MEID_BIN: the meid binary; default
target/release/meid). Exit code 1 when a block fails, naming the file and line.
"""

import os
import pathlib
import re
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
RUN = {"python", "sh", "bash"}
SKIP = re.compile(r"<!--\s*snippet:\s*not run\s*\((.+)\)\s*-->")


def blocks(path):
    """(line, language, code, skip reason or None) of every fenced block of `path`."""
    lines = path.read_text(encoding="utf-8").split("\n")
    out, i = [], 0
    while i < len(lines):
        m = re.match(r"^```(\w*)\s*$", lines[i])
        if not m:
            i += 1
            continue
        lang, start = m.group(1), i + 1
        j = start
        while j < len(lines) and not lines[j].startswith("```"):
            j += 1
        prev = lines[i - 1] if i > 0 else ""
        skip = SKIP.search(prev)
        out.append((start, lang, "\n".join(lines[start:j]) + "\n", skip.group(1) if skip else None))
        i = j + 1
    return out


def run_block(lang, code, cwd, env):
    if lang == "python":
        cmd = [sys.executable, "-c", code]
    else:
        cmd = ["bash", "-euo", "pipefail", "-c", code]
    return subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=900)


def main(argv):
    files = [pathlib.Path(a).resolve() for a in argv] or [ROOT / "README.md"] + sorted(
        (ROOT / "docs").rglob("*.md")
    )
    meid = pathlib.Path(os.environ.get("MEID_BIN", ROOT / "target/release/meid")).resolve()
    if not meid.is_file():
        print(f"snippets: no meid binary at {meid} (build it, or set MEID_BIN)", file=sys.stderr)
        return 1
    bindir = tempfile.mkdtemp(prefix="meid-bin-")
    os.symlink(meid, os.path.join(bindir, "meid"))
    env = dict(os.environ, PATH=bindir + os.pathsep + os.environ["PATH"], MEID_BIN=str(meid))
    failed, ran, skipped = [], 0, []
    for f in files:
        work = tempfile.mkdtemp(prefix="meid-snippets-")
        os.symlink(ROOT / "examples", os.path.join(work, "examples"))
        rel = f.relative_to(ROOT)
        for line, lang, code, skip in blocks(f):
            if lang not in RUN:
                continue
            if skip:
                skipped.append(f"{rel}:{line} ({skip})")
                continue
            t0 = time.monotonic()
            r = run_block(lang, code, work, env)
            ran += 1
            status = "ok" if r.returncode == 0 else f"FAILED (exit {r.returncode})"
            print(f"snippet {rel}:{line} [{lang}] {status} in {time.monotonic() - t0:.1f} s")
            if r.returncode != 0:
                failed.append(f"{rel}:{line}")
                print(r.stdout[-3000:], r.stderr[-3000:], sep="\n", file=sys.stderr)
    print(f"snippets: {ran} run, {len(failed)} failed, {len(skipped)} not run:")
    for s in skipped:
        print(f"  not run: {s}")
    if failed:
        print("failed: " + ", ".join(failed), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
