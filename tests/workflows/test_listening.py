"""Issue 30: a sweep's local cluster listens on the loopback only (the scheduler, its workers and
the dashboard), so that a sweep on a shared head node is not open to the network."""

import ipaddress
import os
from pathlib import Path

from slipchain.sweeps.executor import dask_client


def _processes(pid: int) -> list[int]:
    """``pid`` and its descendants (Linux /proc)."""
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        for task in Path(f"/proc/{p}/task").glob("*"):
            try:
                todo += [int(c) for c in (task / "children").read_text().split()]
            except OSError:
                pass
    return out


def _socket_inodes(pid: int) -> set[str]:
    inodes = set()
    for fd in Path(f"/proc/{pid}/fd").glob("*"):
        try:
            target = os.readlink(fd)
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[8:-1])
    return inodes


def _listening() -> dict[str, str]:
    """inode -> local address of every TCP socket in state LISTEN (/proc/net/tcp, tcp6)."""
    found = {}
    for name, size in (("tcp", 4), ("tcp6", 16)):
        for line in Path(f"/proc/net/{name}").read_text().splitlines()[1:]:
            f = line.split()
            if f[3] != "0A":  # LISTEN
                continue
            hexaddr = f[1].split(":")[0]
            raw = bytes.fromhex(hexaddr)
            raw = b"".join(raw[i:i + 4][::-1] for i in range(0, size, 4))  # little-endian 32-bit words
            found[f[9]] = str(ipaddress.ip_address(raw))
    return found


def test_the_local_cluster_listens_on_the_loopback_only():
    with dask_client(n_workers=1) as client:
        mine = set().union(*(_socket_inodes(p) for p in _processes(os.getpid())))
        addresses = [addr for inode, addr in _listening().items() if inode in mine]
        assert len(addresses) >= 3  # the scheduler, the dashboard, the worker (and its nanny)
        assert all(ipaddress.ip_address(a).is_loopback for a in addresses), addresses
        assert "127.0.0.1" in client.dashboard_link


def test_the_dashboard_address_is_printed_on_request_only(tmp_path):
    """`--dashboard` prints the local cluster's dashboard address (127.0.0.1, a real port) as one line
    on stderr; without it nothing about the dashboard is printed."""
    import re
    import subprocess
    import sys

    definition = tmp_path / "sweep.toml"
    definition.write_text('name = "d"\n[base]\nN = 11\nstart = "steady"\nt_total = 0.05\n[grid]\nseed = [0]\n')
    printed = {}
    for flag in ("--dashboard", None):
        r = subprocess.run([sys.executable, "-m", "slipchain", "sweep", str(definition), "--store",
                            str(tmp_path / ("with" if flag else "without")), "--workers", "1", "--no-progress", *([flag] if flag else [])],
                           capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stderr
        printed[flag] = re.findall(r"^dashboard: http://([0-9.]+):(\d+)/status$", r.stderr, re.M)
        assert "dashboard:" not in r.stdout
    (host, port), = printed["--dashboard"]
    assert ipaddress.ip_address(host).is_loopback and int(port) > 0
    assert printed[None] == []
