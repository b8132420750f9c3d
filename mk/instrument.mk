# The commissioning instrument: the HTTP control API and web panel in dfp-sim
# (libmicrohttpd, cJSON), the panel tested in a real browser (chromium + chromium-driver driven
# by selenium), the Python client and its pytest suite (python/, installed into build/venv).
APT_PACKAGES += libmicrohttpd-dev libcjson-dev chromium chromium-driver curl
