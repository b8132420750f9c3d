# Captures and telemetry: libpcap reads pcap/pcapng, LCM carries telegrams and card
# state between processes (lcm-gen compiles sim_host/lcm_bridge/*.lcm), tshark runs the Lua
# dissector in tools/wireshark/ in the tests. LCM itself is the PyPI wheel in the venv (1.5;
# Debian's 1.3.1 can be crashed by two datagrams, cmake/dfp_lcm.cmake); liblcm needs glib.
APT_PACKAGES += libpcap-dev libglib2.0-dev tshark
# tests/lcm: udpm on loopback in a private network namespace needs ip (unshare is util-linux).
APT_PACKAGES += iproute2
# Keyed LCM segments (--key) sign and check telegrams with libsodium (sim_host/lcm_bridge).
APT_PACKAGES += libsodium-dev
