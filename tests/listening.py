"""What listens on a port of this machine, and on which addresses (Linux ``/proc/net``)."""

from __future__ import annotations

import socket
from pathlib import Path

PROC_NET = Path("/proc/net")
LISTEN = "0A"  # the TCP state LISTEN in /proc/net/tcp


def supported() -> bool:
    """Whether this machine says which addresses its ports listen on (Linux)."""
    return (PROC_NET / "tcp").exists()


def listening_hosts(port: int) -> set[str]:
    """The IPv4 and IPv6 addresses on which something listens at TCP ``port`` here."""
    hosts = set()
    for table, family in (("tcp", socket.AF_INET), ("tcp6", socket.AF_INET6)):
        path = PROC_NET / table
        if not path.exists():
            continue
        for line in path.read_text().splitlines()[1:]:
            local, _, state = line.split()[1:4]
            address, local_port = local.split(":")
            if state == LISTEN and int(local_port, 16) == port:
                raw = bytes.fromhex(address)
                # /proc writes each 32-bit word of the address in host (little-endian) order.
                words = b"".join(raw[i : i + 4][::-1] for i in range(0, len(raw), 4))
                hosts.add(socket.inet_ntop(family, words))
    return hosts


def free_port() -> int:
    """A TCP port nothing listens on now, on 127.0.0.1."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])
