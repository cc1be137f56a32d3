#!/usr/bin/env python3
"""Counts, on the loopback interface, the UDP datagrams that carry given byte strings in clear.

    loopback_sniff.py SECONDS DOMAIN MARKER [MARKER...]

Needs root (an AF_PACKET socket bound to "lo"; nothing else is captured). Only RTPS datagrams
sent to a port of DDS domain DOMAIN (7400 + 250 * DOMAIN + 0..249) are looked at, so other
processes' traffic on lo is left out. Prints "listening" to stderr once capturing, then, at the
end, "rtps datagrams: N" and one line per marker, "MARKER: N datagrams in clear". Used by
run_security_check.sh to show that a protected topic's payload (the probe's sample text) and
its discovery data (the probe's type name) are not readable on the wire, while an unprotected
run shows them.
"""
import socket
import struct
import sys
import time

ETH_P_ALL = 0x0003


def main():
    seconds = float(sys.argv[1])
    first_port = 7400 + 250 * int(sys.argv[2])
    markers = [m.encode() for m in sys.argv[3:]]
    sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETH_P_ALL))
    sock.bind(("lo", 0))
    sock.settimeout(0.2)
    print("listening", file=sys.stderr, flush=True)
    counts = {m: 0 for m in markers}
    total = 0
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        try:
            frame, address = sock.recvfrom(65535)
        except socket.timeout:
            continue
        if address[2] == socket.PACKET_OUTGOING:  # loopback shows each datagram twice
            continue
        if len(frame) < 14 + 20 or struct.unpack("!H", frame[12:14])[0] != 0x0800:
            continue
        ip = frame[14:]
        header = (ip[0] & 0x0F) * 4
        if ip[9] != 17:  # UDP
            continue
        if not first_port <= struct.unpack("!H", ip[header + 2:header + 4])[0] < first_port + 250:
            continue
        payload = ip[header + 8:]
        if not payload.startswith(b"RTPS"):
            continue
        total += 1
        for m in markers:
            if m in payload:
                counts[m] += 1
    print(f"rtps datagrams: {total}")
    for m in markers:
        print(f"{m.decode()}: {counts[m]} datagrams in clear")


if __name__ == "__main__":
    main()
