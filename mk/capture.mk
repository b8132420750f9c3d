# Captures and telemetry: libpcap reads pcap/pcapng, LCM carries telegrams and card
# state between processes (lcm-gen compiles sim_host/lcm/*.lcm), tshark runs the Lua dissector
# in tools/wireshark/ in the tests.
APT_PACKAGES += libpcap-dev liblcm-dev liblcm-bin libglib2.0-dev tshark
# tests/lcm: udpm on loopback in a private network namespace needs ip (unshare is util-linux).
APT_PACKAGES += iproute2
