#!/usr/bin/env python3
"""Runs every command example of README.md and docs/*.md as written, against the embedded simulators.

Every fenced block whose lines call `axon` must be classified by an HTML comment on the line before
its fence (a block without one fails this test, so a new example cannot be forgotten):

    <!-- example: run -->        a shell session: run here, line by line, in a copy of docs/examples/
    <!-- example: synopsis -->   a usage summary with placeholders, not meant to run
    <!-- example: hardware -->   needs a real device (SocketCAN, a gateway at a real address)
    <!-- example: setup -->      the set-up commands themselves (`make run`, `make test`): CI runs them

In a `run` block, each line is one shell command (comments and blank lines skipped). A line ending in
`&` starts a background process: servers and simulators are waited for until they print their
`listening`/`ready` line; `wait` waits for the other background commands. Every foreground command must exit 0 within its time limit; at the end,
every background process still running is sent SIGTERM and must exit 0 (their normal end).

One retry, for one kind of failure only: a 1 kHz blmc example over loopback TCP that a stall of the
machine (tens of ms without a frame, seen on shared CI VMs with nothing else running) stops
with its safety exit code 4 and a stale-data fault. That stop is the host doing its job; the block
runs once more, the retry is printed, and a second failure fails the test.

The block runs with `axon` on PATH in a fresh copy of docs/examples/, so the files the examples name
(traj.yaml, program.yaml, ...) are there as they are for a user who runs them from that folder.

usage: docs_examples.py PATH_TO_AXON [FILE.md ...]
"""
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
KINDS = {"run", "synopsis", "hardware", "setup"}
MARK = re.compile(r"<!--\s*example:\s*([a-z]+)\s*(?:timeout=(\d+))?\s*-->")
FOREGROUND_LIMIT_S = 240
SAFETY_STOP = 4  # the exit code of a command a safety check stopped (docs/getting-started.md)
TIMING_STOP = re.compile(r"safety stop: stale data: no \w+ frame for")
READY_LIMIT_S = 60


class Block:
    def __init__(self, path, line, kind, timeout, lines):
        self.path, self.line, self.kind, self.lines = path, line, kind, lines
        self.timeout = timeout or FOREGROUND_LIMIT_S

    def where(self):
        return f"{os.path.relpath(self.path, ROOT)}:{self.line}"


def blocks_of(path):
    """The fenced blocks of a markdown file that call axon, with their classification (or None)."""
    found, mark, inside, start, body = [], None, False, 0, []
    with open(path, encoding="utf-8") as f:
        text = f.read().splitlines()
    for n, line in enumerate(text, 1):
        if line.startswith("```"):
            if inside:
                if any(re.match(r"\s*axon\s", l) for l in body):
                    kind, timeout = (mark.group(1), int(mark.group(2) or 0)) if mark else (None, 0)
                    found.append(Block(path, start, kind, timeout, body))
                inside, mark, body = False, None, []
            else:
                inside, start = True, n
                prev = text[n - 2].strip() if n >= 2 else ""
                mark = MARK.search(prev)
            continue
        if inside:
            body.append(line)
    return found


BACKGROUND = re.compile(r"^(.*?)\s*&\s*(?:#.*)?$")  # `cmd &` or `cmd &  # comment` (a `#` inside a word is no comment)


def commands(block):
    """(command, background) per line of a run block; bash itself drops trailing comments."""
    out = []
    for line in block.lines:
        cmd = line.strip()
        if not cmd or cmd.startswith("#"):
            continue
        m = BACKGROUND.match(cmd)
        out.append((m.group(1), True) if m else (cmd, False))
    return out


def is_server(cmd):
    return bool(re.search(r"\baxon\s+(sim\s+(fps|blmc|plc)|can\s+bridge|c4g\s+serve)\b", cmd))


def wait_ready(proc, out_path, cmd):
    want = re.compile(r"^ready$" if re.search(r"sim\s+fps\b.*--layout", cmd) else r"^(listening|ready)\b", re.M)
    deadline = time.monotonic() + READY_LIMIT_S
    while time.monotonic() < deadline:
        with open(out_path, encoding="utf-8", errors="replace") as f:
            if want.search(f.read()):
                return None
        if proc.poll() is not None:
            return f"exited with {proc.returncode} before it was ready"
        time.sleep(0.05)
    return f"not ready after {READY_LIMIT_S} s"


def wait_started(proc, out_path, err_path):
    """A background command that is not a server: until it has said something (a dump's "receiving
    on"), as a user would see it start before typing the next line; at most 5 s."""
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline:
        if os.path.getsize(out_path) or os.path.getsize(err_path):
            return None
        if proc.poll() is not None:
            return None if proc.returncode == 0 else f"exited with {proc.returncode}"
        time.sleep(0.05)
    return None


def wait_jobs(background, limit_s):
    """`wait`: the background commands that are not servers must end by themselves, with 0."""
    for cmd, proc, _, err_path in background:
        if is_server(cmd):
            continue
        try:
            rc = proc.wait(timeout=limit_s)
        except subprocess.TimeoutExpired:
            return f"`{cmd}` still running after {limit_s} s at `wait`"
        if rc != 0:
            return f"`{cmd}` (background) exited {rc}\n{tail(err_path)}"
    return None


def tail(path, n=30):
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            return "".join(f.readlines()[-n:])
    except OSError:
        return ""


def run_block_retrying(block, axon):
    """run_block, once more when its only failure was a timing stop; returns (problems, the command
    that stopped on stale data the first time or None)."""
    problems, stopped = run_block(block, axon)
    if not stopped or len(problems) != 1:
        return problems, None
    print(f"RETRY {block.where()}: `{stopped}` stopped on stale data (a stalled machine); running the block again",
          flush=True)
    return run_block(block, axon)[0], stopped


def run_block(block, axon):
    """Runs one block; returns (a list of problems (empty: passed), the foreground command that ended
    the block with a stale-data safety stop or None)."""
    work = tempfile.mkdtemp(prefix="axon-docs-")
    problems, background, timing_stop = [], [], None
    try:
        shutil.copytree(os.path.join(ROOT, "docs", "examples"), work, dirs_exist_ok=True)
        bindir = os.path.join(work, ".bin")
        os.makedirs(bindir)
        os.symlink(os.path.abspath(axon), os.path.join(bindir, "axon"))
        env = dict(os.environ, PATH=bindir + os.pathsep + os.environ.get("PATH", ""))
        for i, (cmd, bg) in enumerate(commands(block)):
            if cmd == "wait":  # as in a shell session: the background commands that end by themselves
                why = wait_jobs(background, block.timeout)
                if why:
                    problems.append(why)
                    break
                continue
            out_path, err_path = os.path.join(work, f".{i}.out"), os.path.join(work, f".{i}.err")
            with open(out_path, "w") as out, open(err_path, "w") as err:
                proc = subprocess.Popen(["bash", "-c", cmd], cwd=work, env=env, stdout=out, stderr=err,
                                        start_new_session=bg)
            if bg:
                background.append((cmd, proc, out_path, err_path))
                why = wait_ready(proc, out_path, cmd) if is_server(cmd) else wait_started(proc, out_path, err_path)
                if why:
                    problems.append(f"`{cmd}` {why}\n{tail(err_path)}")
                    break
                continue
            try:
                rc = proc.wait(timeout=block.timeout)
            except subprocess.TimeoutExpired:
                proc.kill()
                problems.append(f"`{cmd}` still running after {block.timeout} s")
                break
            if rc != 0:
                if rc == SAFETY_STOP and TIMING_STOP.search(tail(err_path)):
                    timing_stop = cmd
                problems.append(f"`{cmd}` exited {rc}\n--- stdout\n{tail(out_path)}--- stderr\n{tail(err_path)}")
                break
        for cmd, proc, out_path, err_path in reversed(background):
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGTERM)
                try:
                    rc = proc.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    os.killpg(proc.pid, signal.SIGKILL)
                    problems.append(f"`{cmd}` did not stop within 30 s of SIGTERM")
                    continue
            else:
                rc = proc.returncode
            if rc != 0:
                problems.append(f"`{cmd}` (background) exited {rc}\n{tail(err_path)}")
    finally:
        for _, proc, _, _ in background:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
        shutil.rmtree(work, ignore_errors=True)
    return problems, timing_stop


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    axon = sys.argv[1]
    files = sys.argv[2:] or [os.path.join(ROOT, "README.md")] + sorted(
        os.path.join(ROOT, "docs", f) for f in os.listdir(os.path.join(ROOT, "docs")) if f.endswith(".md"))
    failures, ran, skipped, retries = [], 0, {}, []
    for path in files:
        for block in blocks_of(path):
            if block.kind not in KINDS:
                failures.append(f"{block.where()}: a block of axon commands without `<!-- example: run|synopsis|hardware|setup -->`")
                continue
            if block.kind != "run":
                skipped[block.kind] = skipped.get(block.kind, 0) + 1
                continue
            t0 = time.monotonic()
            problems, retried = run_block_retrying(block, axon)
            ran += 1
            retries += [f"{block.where()}: `{retried}`"] if retried else []
            print(f"{'FAIL' if problems else 'ok  '} {block.where()} ({time.monotonic() - t0:.1f} s)", flush=True)
            failures += [f"{block.where()}: {p}" for p in problems]
    print(f"{ran} example blocks run; not run: " + ", ".join(f"{n} {k}" for k, n in sorted(skipped.items())))
    for r in retries:
        print("retried once after a stale-data safety stop:", r)
    for f in failures:
        print("FAIL:", f, file=sys.stderr)
    if not failures:
        print("PASS")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
