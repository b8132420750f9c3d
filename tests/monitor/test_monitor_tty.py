"""dfp-sim monitor --view top on a terminal (a PTY): every key that ends it gives the terminal
back as it was (the alternate screen left, the cursor shown, line editing and echo on), Ctrl-\\
(SIGQUIT, were it a signal: killed with the terminal raw) and Ctrl-C included.

Usage: test_monitor_tty.py DFP_SIM
"""
import os
import select
import signal
import subprocess
import sys
import tempfile
import termios
import time

SIM = sys.argv[1]
failed = 0
passed = 0


def check(cond, what):
    global failed, passed
    if cond:
        passed += 1
    else:
        failed += 1
        print("FAIL:", what, file=sys.stderr)


def run_top(port, key):
    """The monitor on a PTY, key typed after a second; its output, how it ended, the PTY's
    settings after."""
    pid, fd = os.forkpty()
    if pid == 0:
        os.execv(SIM, [SIM, "monitor", "--port", port, "--baud", "187500", "--view", "top",
                       "--seconds", "20"])
    out = b""

    def drain(seconds, until=None):
        nonlocal out
        end = time.time() + seconds
        while time.time() < end and (until is None or until not in out):
            r, _, _ = select.select([fd], [], [], 0.05)
            if r:
                try:
                    out += os.read(fd, 65536)
                except OSError:
                    return

    drain(10.0, until=b"\x1b[?1049h")  # the view is up
    drain(0.5)
    os.write(fd, key)
    done, status = 0, 0
    for _ in range(30):  # up to 3 s
        drain(0.1)
        time.sleep(0.02)  # the PTY reads EIO at once when the monitor closed it
        done, status = os.waitpid(pid, os.WNOHANG | os.WUNTRACED)
        if done != 0:
            break
    lflag = termios.tcgetattr(fd)[3]
    if done == 0 or os.WIFSTOPPED(status):
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
    os.close(fd)
    return out, done != 0, status, lflag


with tempfile.TemporaryDirectory() as tmp:
    line = subprocess.Popen([SIM, "line", "--dir", tmp, "--ports", "1", "--baud", "187500",
                             "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    try:
        for _ in range(50):
            if os.path.exists(os.path.join(tmp, "port1")):
                break
            time.sleep(0.1)
        port = os.path.join(tmp, "port1")
        for name, key in (("q", b"q"), ("Ctrl-C", b"\x03"), ("Ctrl-\\", b"\x1c")):
            out, ended, status, lflag = run_top(port, key)
            check(ended and os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0,
                  f"{name}: the monitor ends with exit 0 (ended {ended}, status {status})")
            check(b"\x1b[?1049l" in out and b"\x1b[?25h" in out,
                  f"{name}: the alternate screen left and the cursor shown")
            check(lflag & termios.ICANON and lflag & termios.ECHO,
                  f"{name}: line editing and echo back on")
    finally:
        line.terminate()
        line.wait()

print(f"{passed} passed, {failed} failed")
sys.exit(1 if failed or not passed else 0)
