"""The client against the real dfp-sim's security (docs/api.md, "Security"): the token DfpSim
gives each child, what the server says without it, the viewer's refused actions, --http-no-auth,
and HTTPS with a self-signed certificate made here by openssl."""

import shutil
import ssl
import subprocess

import pytest

from dfpsim import ApiError, AuthError, Client, DfpSim, TlsError, wait_until

NEED_TOKEN = ("a token is needed: open the URL dfp-sim printed at start, or send "
              "Authorization: Bearer TOKEN")
VIEWER_REFUSED = "this needs the operator role; this client is a viewer"
VIEWER_TOKEN = "python-test-viewer-0123456789abcdef"


def test_without_the_token_the_server_says_what_it_wants(demo):
    assert demo.token and len(demo.token) == 43
    anon = Client(demo.base_url, token="")
    with pytest.raises(AuthError) as e:
        anon.state()
    assert (e.value.status, e.value.message) == (401, NEED_TOKEN)
    with pytest.raises(AuthError) as e:
        Client(demo.base_url, token="wrong-token-0123456789abcdef").master().stop()
    assert (e.value.status, e.value.message) == (401, NEED_TOKEN)
    with pytest.raises(AuthError) as e:
        next(anon.events(timeout=5))
    assert (e.value.status, e.value.message) == (401, NEED_TOKEN)
    assert demo.master().running is True, "a refused request stopped the master"


def test_the_token_from_the_environment(demo, monkeypatch):
    monkeypatch.setenv("DFP_SIM_TOKEN", demo.token)
    assert Client(demo.base_url).state()["mode"] == "demo"
    monkeypatch.setenv("DFP_SIM_TOKEN", "not-the-token-0123456789")
    with pytest.raises(AuthError):
        Client(demo.base_url).state()


def test_a_viewer_reads_but_every_action_is_refused(dfp_sim, monkeypatch):
    monkeypatch.setenv("DFP_SIM_VIEWER_TOKEN", VIEWER_TOKEN)   # passed on to the child
    with DfpSim.demo(dfp_sim=dfp_sim) as sim:
        viewer = Client(sim.base_url, token=VIEWER_TOKEN)
        assert viewer.state()["mode"] == "demo"
        assert viewer.card(4).read_param("P130").p_number == "P130"
        events = viewer.events(timeout=5)
        try:
            assert next(events)["event"] in ("state", "log")
        finally:
            events.close()
        actions = (lambda: viewer.master().stop(),
                   lambda: viewer.card(4).set_input("DI00", False),
                   lambda: viewer.card(4).write_param("P130", 500),
                   lambda: viewer.master().read_param(4, "P100"))
        for action in actions:
            with pytest.raises(ApiError) as e:
                action()
            assert (e.value.status, e.value.message) == (403, VIEWER_REFUSED)
            assert not isinstance(e.value, AuthError)
        st = sim.state()
        assert st["master"]["running"] is True
        assert st["cards"][0]["drive"]["inputs"]["DI00"] is True


def test_no_auth_on_loopback_needs_no_token(dfp_sim):
    with DfpSim.demo(dfp_sim=dfp_sim, extra_args=("--http-no-auth",)) as sim:
        anon = Client(sim.base_url, token="")
        assert anon.get("/api/v1/session") == {"auth": False, "role": "operator"}
        anon.master().stop()
        wait_until(lambda: sim.master().running is False, timeout=5, what="master in STOP")
        anon.master().run()
        wait_until(lambda: sim.master().running is True, timeout=5, what="master in RUN")


def make_certificate(tmp_path, name):
    """A self-signed certificate for 127.0.0.1 and its key (PEM files)."""
    if shutil.which("openssl") is None:
        pytest.fail("openssl is needed to make a test certificate (apt-get install openssl)")
    cert, key = tmp_path / (name + ".crt"), tmp_path / (name + ".key")
    subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2",
                    "-subj", "/CN=127.0.0.1", "-addext", "subjectAltName=IP:127.0.0.1",
                    "-keyout", str(key), "-out", str(cert)],
                   check=True, capture_output=True, timeout=60)
    return cert, key


def test_https_with_the_certificate_as_cafile(dfp_sim, tmp_path):
    cert, key = make_certificate(tmp_path, "server")
    other, _ = make_certificate(tmp_path, "other")
    with DfpSim.demo(dfp_sim=dfp_sim, tls=(cert, key)) as sim:
        assert sim.base_url.startswith("https://127.0.0.1:")
        assert sim.state()["mode"] == "demo"
        events = sim.events(timeout=5)
        try:
            assert next(events)["event"] in ("state", "log")
        finally:
            events.close()
        # without the certificate (the system's CAs) or with another one: not verified
        for cafile in (None, other):
            c = Client(sim.base_url, token=sim.token, cafile=cafile)
            with pytest.raises(TlsError) as e:
                c.state()
            assert isinstance(e.value.reason, ssl.SSLCertVerificationError), e.value.reason
            assert "certificate verify failed" in str(e.value)
            with pytest.raises(TlsError):
                next(c.events(timeout=5))
        # the token is still needed over TLS
        with pytest.raises(AuthError):
            Client(sim.base_url, token="", cafile=cert).state()
