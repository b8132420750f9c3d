# The commissioning instrument: the HTTP control API and web panel in dfp-sim
# (libmicrohttpd with GnuTLS for HTTPS, cJSON, libsodium for tokens and sessions), the panel
# tested in a real browser (chromium + chromium-driver driven by selenium), the Python client and
# its pytest suite (python/, installed into build/venv); openssl makes the tests' certificates.
APT_PACKAGES += libmicrohttpd-dev libcjson-dev libsodium-dev chromium chromium-driver curl openssl
