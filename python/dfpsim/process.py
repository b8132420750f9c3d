"""Starting and stopping dfp-sim processes (and the socat PTY pair between them)."""

import os
import secrets
import shutil
import signal
import socket
import subprocess
import tempfile
import time
import urllib.error

from .client import API, TOKEN_ENV, Client
from .errors import ApiError, DfpSimError, TlsError

EXIT_PORT_TAKEN = 2  # docs/api.md: a taken port is a one-line error and exit 2


def find_dfp_sim(dfp_sim=None):
    """The dfp-sim binary: the argument, else $DFP_SIM, else `dfp-sim` on PATH."""
    path = dfp_sim or os.environ.get("DFP_SIM") or shutil.which("dfp-sim")
    if not path:
        raise DfpSimError("where is dfp-sim? pass dfp_sim=PATH or set $DFP_SIM (e.g. "
                          "build/host/sim_host/dfp_sim/dfp-sim)")
    path = os.fspath(path)
    if not (os.path.isfile(path) and os.access(path, os.X_OK)):
        raise DfpSimError("dfp-sim is not an executable file: %s" % path)
    return path


def free_port(host="127.0.0.1"):
    """A TCP port nobody listens on right now (the OS picks it)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return s.getsockname()[1]


def _tail(path, lines=30):
    try:
        with open(path, "r", errors="replace") as f:
            return "".join(f.readlines()[-lines:])
    except OSError:
        return ""


class Process:
    """One child process whose stdout and stderr go to files in a directory."""

    def __init__(self, name, argv, workdir, env=None):
        self.name = name
        self.argv = [os.fspath(a) for a in argv]
        self.stdout_path = os.path.join(workdir, name + ".out")
        self.stderr_path = os.path.join(workdir, name + ".err")
        with open(self.stdout_path, "wb") as out, open(self.stderr_path, "wb") as err:
            self.popen = subprocess.Popen(self.argv, stdin=subprocess.DEVNULL, stdout=out,
                                          stderr=err, env=env)
        self.returncode = None

    @property
    def pid(self):
        return self.popen.pid

    def poll(self):
        return self.popen.poll()

    def stop(self, sig=signal.SIGINT, timeout=5.0):
        """`sig`, wait up to `timeout` s, then SIGKILL. Returns the exit code (None: killed)."""
        if self.popen.poll() is None:
            try:
                self.popen.send_signal(sig)
                self.returncode = self.popen.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.popen.kill()
                self.popen.wait()
                self.returncode = None
        else:
            self.returncode = self.popen.returncode
        return self.returncode

    def output(self):
        """What the process printed so far (stdout, then stderr)."""
        return _tail(self.stdout_path, 10 ** 9) + _tail(self.stderr_path, 10 ** 9)

    def describe(self, lines=30):
        return "%s (%s):\n--- stdout (last %d lines)\n%s--- stderr (last %d lines)\n%s" % (
            self.name, " ".join(self.argv), lines, _tail(self.stdout_path, lines), lines,
            _tail(self.stderr_path, lines))


def _wait_api(proc, client, timeout):
    """Until GET /api/v1/state answers; DfpSimError if the process ends or time runs out."""
    end = time.monotonic() + timeout
    last = None
    while time.monotonic() < end:
        rc = proc.poll()
        if rc is not None:
            return rc
        try:
            client.request("GET", API + "/state", timeout=1.0)
            return None
        except TlsError:
            proc.stop(signal.SIGKILL)
            raise
        except (OSError, ApiError, urllib.error.URLError) as e:
            last = e
        time.sleep(0.05)
    proc.stop(signal.SIGKILL)
    raise DfpSimError("%s: GET %s/state did not answer within %.0f s (last: %s)\n%s"
                      % (proc.name, client.base_url, timeout, last, proc.describe()))


class _Session:
    """The processes of one `with` block, stopped in reverse order on exit."""

    def __init__(self, dfp_sim, check_exit, startup_timeout, stop_timeout):
        self.dfp_sim = find_dfp_sim(dfp_sim)
        self.check_exit = check_exit
        self.startup_timeout = startup_timeout
        self.stop_timeout = stop_timeout
        self.workdir = None
        self.processes = []   # (Process, must exit 0)
        self._own_workdir = False

    def _mkworkdir(self, workdir=None):
        if workdir is None:
            self.workdir = tempfile.mkdtemp(prefix="dfpsim-")
            self._own_workdir = True
        else:
            self.workdir = os.fspath(workdir)
            os.makedirs(self.workdir, exist_ok=True)

    def start_sim(self, name, args, http_port=None, tls=None):
        """dfp-sim ARGS --http 127.0.0.1:PORT, up to a first answer of the API -> Client.

        The child gets a new operator token ($DFP_SIM_TOKEN in its environment; the rest of
        the environment is passed on, $DFP_SIM_VIEWER_TOKEN included), and the Client sends
        it. tls=(CERT, KEY): --http-cert/--http-key, and the Client trusts CERT."""
        tries = 1 if http_port else 3
        token = secrets.token_urlsafe(32)
        env = dict(os.environ, **{TOKEN_ENV: token})
        extra, scheme, cafile = [], "http", None
        if tls is not None:
            cafile = os.fspath(tls[0])
            extra, scheme = ["--http-cert", cafile, "--http-key", os.fspath(tls[1])], "https"
        for attempt in range(tries):
            port = http_port or free_port()
            argv = [self.dfp_sim] + list(args) + ["--http", "127.0.0.1:%d" % port] + extra
            proc = Process(name, argv, self.workdir, env=env)
            client = Client("%s://127.0.0.1:%d" % (scheme, port), token=token, cafile=cafile)
            rc = _wait_api(proc, client, self.startup_timeout)
            if rc is None:
                self.processes.append((proc, True))
                return client
            if rc == EXIT_PORT_TAKEN and attempt + 1 < tries and not http_port:
                continue  # someone took the free port in between: another one
            raise DfpSimError("%s exited with %d before its API answered\n%s"
                              % (name, rc, proc.describe()))
        raise AssertionError("unreachable")

    def start_other(self, name, argv):
        proc = Process(name, argv, self.workdir)
        self.processes.append((proc, False))
        return proc

    def outputs(self, lines=40):
        """{name: the last `lines` lines it printed} for every process of the session."""
        return {proc.name: _tail(proc.stdout_path, lines) + _tail(proc.stderr_path, lines)
                for proc, _ in self.processes}

    def stop(self):
        """Stops everything; returns a list of complaints (exit codes that were not 0)."""
        complaints = []
        for proc, checked in reversed(self.processes):
            rc = proc.stop(signal.SIGINT if checked else signal.SIGTERM, self.stop_timeout)
            if checked and rc != 0:
                why = "killed after %.0f s" % self.stop_timeout if rc is None else "exit %d" % rc
                complaints.append("%s: %s on SIGINT\n%s" % (proc.name, why, proc.describe()))
        self.processes = []
        return complaints

    def close(self, exc):
        """Stops everything and removes the session's own directory. A complaint raises
        DfpSimError unless check_exit is off or the body already failed (then it becomes a
        note on that exception)."""
        complaints = self.stop()
        if self._own_workdir:
            shutil.rmtree(self.workdir, ignore_errors=True)
        if exc is not None:
            for c in complaints:
                exc.add_note(c)
        elif complaints and self.check_exit:
            raise DfpSimError("\n".join(complaints))


class SlaveAndMaster:
    """What DfpSim.slave_and_master() yields: `.slave` and `.master` Clients, and the rest."""

    def __init__(self, session, slave, master, address, port_slave, port_master, eeprom):
        self._session = session
        self.slave = slave
        self.master = master
        self.address = address
        self.port_slave = port_slave    # the PTY the card is on
        self.port_master = port_master  # the PTY the master is on
        self.eeprom = eeprom
        self.workdir = session.workdir

    @property
    def card(self):
        """The card (and drive) in `dfp-sim slave`."""
        return self.slave.card(self.address)

    @property
    def plc(self):
        """The DP master in `dfp-sim master`."""
        return self.master.master()

    @property
    def session(self):
        return self._session

    def output(self, which):
        """What `slave`, `master` or `socat` printed so far."""
        for proc, _ in self._session.processes:
            if proc.name == which:
                return proc.output()
        raise KeyError(which)


class _Managed:
    """A context manager around a start function; no generator, so a failing body is never
    masked by a complaint about exit codes (the complaint becomes a note on it instead)."""

    def __init__(self, session, start):
        self._session = session
        self._start = start

    def __enter__(self):
        try:
            return self._start(self._session)
        except BaseException:
            self._session.stop()
            if self._session._own_workdir:
                shutil.rmtree(self._session.workdir, ignore_errors=True)
            raise

    def __exit__(self, exc_type, exc, tb):
        self._session.close(exc)
        return False


class DfpSim:
    """Context managers that start dfp-sim with --http and stop it again.

        with DfpSim.demo() as sim:                       # sim is a Client
            print(sim.card(4).dp_state)

        with DfpSim.slave_and_master(address=4) as bus:  # bus.slave, bus.master: Clients
            bus.master.master().set_po(4, [0x0006, 1500])

    On exit every process gets SIGINT, up to 5 s to end, then SIGKILL; an exit code other than
    0 raises DfpSimError (check_exit=False: don't), with the last lines the process printed.
    Output goes to files in a temporary directory (`workdir=` to choose one that is kept).
    """

    @staticmethod
    def run(*args, http_port=None, dfp_sim=None, check_exit=True, startup_timeout=10.0,
            stop_timeout=5.0, workdir=None, tls=None):
        """Any `dfp-sim ARGS --http PORT` -> a Client (e.g. DfpSim.run("replay", "x.pcap")).

        The Client carries the token dfp-sim was started with (`client.token`). tls=(CERT,
        KEY): HTTPS with these PEM files, the Client trusting CERT (a self-signed one)."""
        session = _Session(dfp_sim, check_exit, startup_timeout, stop_timeout)

        def start(s):
            s._mkworkdir(workdir)
            client = s.start_sim(str(args[0]) if args else "dfp-sim", args, http_port, tls)
            client.session = s   # outputs() for a test report
            return client

        return _Managed(session, start)

    @staticmethod
    def demo(http_port=None, dfp_sim=None, check_exit=True, extra_args=(), **kw):
        """`dfp-sim demo --http PORT` (a free port unless given) -> a Client."""
        return DfpSim.run("demo", *extra_args, http_port=http_port, dfp_sim=dfp_sim,
                          check_exit=check_exit, **kw)

    @staticmethod
    def slave_and_master(address=4, config="F3F2", baud=19200, eeprom=None,
                         extra_slave_args=(), extra_master_args=(), dfp_sim=None,
                         check_exit=True, startup_timeout=10.0, stop_timeout=5.0, workdir=None,
                         slave_baud=None):
        """A card (`dfp-sim slave`) and a PLC (`dfp-sim master`) on a socat PTY pair.

        The master sends at `baud` with configuration `config` (hex; "F3F2" = Param + 3 PD)
        and runs until stopped (--cycles 0). The card gets `--baud` `slave_baud` (default:
        `baud`): a PTY has no line rate, so a searching card would lock onto the first rate it
        tries; slave_baud="auto" lets it search anyway. `eeprom`: the drive's EEPROM file
        (default: a new one in the session's directory, so the drive starts from factory
        settings and keeps what is written non-volatile for the session). Yields a
        SlaveAndMaster with `.slave` and `.master` (Clients), `.card` and `.plc`.
        """
        if shutil.which("socat") is None:
            raise DfpSimError("socat is needed for the PTY pair (apt-get install socat)")
        session = _Session(dfp_sim, check_exit, startup_timeout, stop_timeout)

        def start(s):
            s._mkworkdir(workdir)
            a = os.path.join(s.workdir, "pty-slave")
            b = os.path.join(s.workdir, "pty-master")
            for p in (a, b):
                if os.path.lexists(p):
                    os.unlink(p)
            socat = s.start_other("socat", ["socat", "-d", "-d", "pty,raw,echo=0,link=" + a,
                                            "pty,raw,echo=0,link=" + b])
            end = time.monotonic() + 5.0
            while not (os.path.exists(a) and os.path.exists(b)):
                if socat.poll() is not None or time.monotonic() > end:
                    raise DfpSimError("socat did not make the PTY pair\n" + socat.describe())
                time.sleep(0.02)
            ee = os.fspath(eeprom) if eeprom is not None else os.path.join(s.workdir,
                                                                            "drive.eeprom")
            slave = s.start_sim("slave", ["slave", "--port", a, "--address", str(address),
                                          "--baud", str(slave_baud or baud), "--eeprom", ee]
                                + list(extra_slave_args))
            master = s.start_sim("master", ["master", "--port", b, "--address", str(address),
                                            "--config", config, "--baud", str(baud),
                                            "--cycles", "0"] + list(extra_master_args))
            return SlaveAndMaster(s, slave, master, address, a, b, ee)

        return _Managed(session, start)
