#!/usr/bin/env python3
"""Runs the shell blocks of the repository's Markdown files that are marked as runnable.

A block is runnable when its fence's info string is `sh runnable` or `bash runnable`,
optionally followed by `timeout=S` and `needs=CMD[,CMD...]` (programs beyond the base
system: the block is skipped, and says so, where one of them is not on PATH). Each one runs
as a bash script with -euo pipefail:

- in a fresh temporary directory that looks like the repository root: every top-level entry
  of the repository (but build/ and .git) is a symbolic link to the real one, build/host
  points at the build directory given on the command line and build/venv at the
  repository's build/venv, so a block is written as a reader types it from the root
  (`build/host/sim_host/dfp_sim/dfp-sim ...`); what it writes lands in the temporary
  directory;
- with the build's dfp-sim first on PATH and $REPO set to the repository root;
- in a process group of its own, ended after the block; a block that leaves a process
  running fails (the reader's copy would leave it running too), as does one that runs
  longer than its timeout (60 s unless the info string says timeout=S).

The whole run holds an exclusive lock (/tmp/dfp-doc-blocks.lock), so blocks may use fixed
paths such as the PTY pair /tmp/dfp-a, /tmp/dfp-b the docs show, even when two builds run
the test at the same time.

Exit 0 when every block passed, 1 when one failed (file:line and its output are printed)
or when no block was found at all, 2 on a bad command line.
"""

import argparse
import fcntl
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

DEFAULT_TIMEOUT = 60.0
LOCK_PATH = "/tmp/dfp-doc-blocks.lock"
SKIP_DIRS = {"build", ".git", "node_modules", "__pycache__"}
FENCE = re.compile(r"^( {0,3})(`{3,}|~{3,})(.*)$")


class Block:
    def __init__(self, path, line, info, text):
        self.path = path  # relative to the repository
        self.line = line  # 1-based line of the opening fence
        self.info = info
        self.text = text

    def where(self):
        return f"{self.path}:{self.line}"

    def missing(self):
        m = re.search(r"\bneeds=(\S+)", self.info)
        return [c for c in (m.group(1).split(",") if m else []) if shutil.which(c) is None]

    def timeout(self):
        m = re.search(r"\btimeout=(\d+(?:\.\d+)?)\b", self.info)
        return float(m.group(1)) if m else DEFAULT_TIMEOUT


def is_runnable(info):
    words = info.split()
    return len(words) >= 2 and words[0] in ("sh", "bash") and "runnable" in words[1:]


def blocks_in(repo, rel):
    """The runnable blocks of one Markdown file (CommonMark fences: ``` or ~~~, at most three
    spaces of indentation, closed by a fence of the same character at least as long)."""
    with open(os.path.join(repo, rel), encoding="utf-8") as f:
        lines = f.read().split("\n")
    found = []
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m or (m.group(2)[0] == "`" and "`" in m.group(3)):
            i += 1
            continue
        indent, fence, info = len(m.group(1)), m.group(2), m.group(3).strip()
        j = i + 1
        close = re.compile(r"^ {0,3}" + re.escape(fence[0]) + "{" + str(len(fence)) + r",}\s*$")
        while j < len(lines) and not close.match(lines[j]):
            j += 1
        if is_runnable(info):
            body = []
            for line in lines[i + 1 : j]:
                strip = len(line) - len(line.lstrip(" "))
                body.append(line[min(strip, indent) :])
            found.append(Block(rel, i + 1, info, "\n".join(body) + "\n"))
        i = j + 1
    return found


def markdown_files(repo):
    out = []
    for root, dirs, files in os.walk(repo):
        dirs[:] = sorted(d for d in dirs if d not in SKIP_DIRS and not d.startswith("."))
        for name in sorted(files):
            if name.endswith(".md"):
                out.append(os.path.relpath(os.path.join(root, name), repo))
    return out


def make_root(repo, build, venv):
    """A temporary directory that looks like the repository root (see the module text)."""
    tmp = tempfile.mkdtemp(prefix="doc-block-")
    for name in os.listdir(repo):
        if name not in ("build", ".git"):
            os.symlink(os.path.join(repo, name), os.path.join(tmp, name))
    os.mkdir(os.path.join(tmp, "build"))
    os.symlink(build, os.path.join(tmp, "build", "host"))
    if os.path.isdir(venv):
        os.symlink(venv, os.path.join(tmp, "build", "venv"))
    return tmp


def group_members(pgid):
    """Processes still in the process group, as "pid command" lines (from /proc)."""
    members = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", encoding="utf-8", errors="replace") as f:
                stat = f.read()
            fields = stat[stat.rindex(")") + 2 :].split()
            if int(fields[2]) != pgid or fields[0] == "Z":
                continue
            with open(f"/proc/{entry}/cmdline", "rb") as f:
                cmd = f.read().replace(b"\0", b" ").decode(errors="replace").strip()
            members.append(f"{entry} {cmd}")
        except (OSError, ValueError, IndexError):
            continue  # gone meanwhile
    return members


def kill_group(pgid):
    for sig, pause in ((signal.SIGTERM, 1.0), (signal.SIGKILL, 0.0)):
        try:
            os.killpg(pgid, sig)
        except ProcessLookupError:
            return
        end = time.monotonic() + pause
        while time.monotonic() < end and group_members(pgid):
            time.sleep(0.05)


def run_block(block, repo, build, venv, env):
    """(ok, seconds, output, why) for one block."""
    root = make_root(repo, build, venv)
    scratch = tempfile.mkdtemp(prefix="doc-block-script-")
    script = os.path.join(scratch, "block.sh")
    log_path = os.path.join(scratch, "output")
    with open(script, "w", encoding="utf-8") as f:
        f.write(block.text)
    why = None
    start = time.monotonic()
    try:
        with open(log_path, "wb") as log:
            # Output to a file, not a pipe: a background process the block forgets would hold
            # a pipe open and make the wait hang.
            proc = subprocess.Popen(["bash", "-euo", "pipefail", script], cwd=root, env=env,
                                    stdin=subprocess.DEVNULL, stdout=log,
                                    stderr=subprocess.STDOUT, start_new_session=True)
            try:
                rc = proc.wait(timeout=block.timeout())
            except subprocess.TimeoutExpired:
                kill_group(proc.pid)
                proc.wait()
                rc = None
                why = f"did not finish within {block.timeout():g} s"
        seconds = time.monotonic() - start
        if rc is not None and rc != 0:
            why = f"exit status {rc}"
        end = time.monotonic() + 2.0  # a process told to stop may still be on its way out
        left = group_members(proc.pid)
        while left and time.monotonic() < end:
            time.sleep(0.05)
            left = group_members(proc.pid)
        if left:
            kill_group(proc.pid)
            if why is None:
                why = "left processes running (stop them in the block): " + "; ".join(left)
        with open(log_path, encoding="utf-8", errors="replace") as f:
            output = f.read()
    finally:
        shutil.rmtree(root, ignore_errors=True)
        shutil.rmtree(scratch, ignore_errors=True)
    return why is None, seconds, output, why


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("build", help="the build directory (holds sim_host/dfp_sim/dfp-sim)")
    ap.add_argument("--repo", default=os.path.normpath(os.path.join(here, "..", "..")),
                    help="the repository root (default: two levels above this script)")
    ap.add_argument("--only", metavar="FILE[:LINE]",
                    help="run only the blocks of FILE (relative to the root), or the one at LINE")
    ap.add_argument("--list", action="store_true", help="list the blocks, run nothing")
    ap.add_argument("--verbose", action="store_true", help="print every block's output")
    args = ap.parse_args()

    repo = os.path.abspath(args.repo)
    build = os.path.abspath(args.build)
    sim = os.path.join(build, "sim_host", "dfp_sim", "dfp-sim")
    if not os.access(sim, os.X_OK):
        print(f"run_doc_blocks: {sim} is not an executable: give the build directory", file=sys.stderr)
        return 2

    blocks = [b for rel in markdown_files(repo) for b in blocks_in(repo, rel)]
    if args.only:
        blocks = [b for b in blocks if args.only in (b.path, b.where())]
    if not blocks:
        print("run_doc_blocks: no runnable block found (fence info string 'sh runnable')"
              + (f" matching {args.only}" if args.only else ""), file=sys.stderr)
        return 1
    if args.list:
        for b in blocks:
            print(b.where())
        return 0

    env = dict(os.environ)
    env["PATH"] = os.path.dirname(sim) + os.pathsep + env.get("PATH", "/usr/bin:/bin")
    env["REPO"] = repo
    venv = os.path.join(repo, "build", "venv")

    failed = 0
    skipped = 0
    total_start = time.monotonic()
    with open(LOCK_PATH, "a", encoding="utf-8") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        for b in blocks:
            if b.missing():
                skipped += 1
                print(f"skip  {b.where()}: needs {', '.join(b.missing())}, not on PATH")
                continue
            ok, seconds, output, why = run_block(b, repo, build, venv, env)
            if ok:
                print(f"ok    {b.where()} ({seconds:.1f} s)")
                if args.verbose:
                    print("".join(f"    > {line}\n" for line in output.rstrip("\n").split("\n")), end="")
                continue
            failed += 1
            print(f"FAIL  {b.where()}: {why} ({seconds:.1f} s)")
            print("  the block:")
            print("".join(f"    | {line}\n" for line in b.text.rstrip("\n").split("\n")), end="")
            print("  its output:" if output.strip() else "  its output: (none)")
            if output.strip():
                print("".join(f"    > {line}\n" for line in output.rstrip("\n").split("\n")), end="")
    print(f"{len(blocks) - failed - skipped} passed, {failed} failed, {skipped} skipped "
          f"({len(blocks)} blocks, {time.monotonic() - total_start:.1f} s)")
    return 1 if failed or skipped == len(blocks) else 0


if __name__ == "__main__":
    sys.exit(main())
