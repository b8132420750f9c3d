"""Exceptions of the dfpsim client."""


class DfpSimError(Exception):
    """Base class of everything this package raises on its own account."""


class ApiError(DfpSimError):
    """The control API answered with an HTTP error (docs/api.md, "Ground rules").

    `status` is the HTTP status (400 bad request, 401 no or wrong token (AuthError), 403
    read-only server or a viewer's action, 404 unknown card or route, 405 wrong method, 409
    action this process cannot do, 415 not JSON, 504 parameter service without answer),
    `message` the server's `{"error": ...}` text, `method` and `path` the request.
    """

    def __init__(self, status, message, method=None, path=None):
        self.status = status
        self.message = message
        self.method = method
        self.path = path
        where = "%s %s: " % (method, path) if method and path else ""
        super().__init__("%sHTTP %s: %s" % (where, status, message))


class ParamError(ApiError):
    """The drive refused a parameter service; `message` is the MOVILINK error text.

    From the master (`POST /api/v1/master/param`) the service itself worked, so `status` is
    200; from a card's direct access (`PUT /api/v1/cards/{a}/params/{p}`) it is 400. `answer`
    is the server's whole JSON answer (with `p_number`, `index`, `name` where it gave them).
    """

    def __init__(self, status, message, answer=None, method=None, path=None):
        self.answer = dict(answer or {})
        self.p_number = self.answer.get("p_number")
        super().__init__(status, message, method, path)


class AuthError(ApiError):
    """401: the server wants a token and got none or a wrong one (docs/api.md, "Security").

    Give the Client `token=` (the one dfp-sim printed at start, or read with
    --http-token-file), or set $DFP_SIM_TOKEN. `message` is the server's text.
    """


class TlsError(DfpSimError):
    """The https server could not be verified (or the TLS handshake failed); `reason` is the
    ssl module's exception. A self-signed certificate needs `Client(..., cafile=CERT)`."""

    def __init__(self, url, reason):
        self.url = url
        self.reason = reason
        super().__init__("%s: TLS: %s (for a self-signed certificate give cafile=, the "
                         "certificate or the CA that signed it)" % (url, reason))
