#!/usr/bin/python3
"""phri's ROS 2 bridge across two machines: two Linux network namespaces joined by a virtual
Ethernet link stand for the controller's machine (phri) and another one (the Fast DDS peer).
Neither sees the other's loopback, so everything the peer checks crossed the link; the link's
packet counters are read before and after to show that it did.

  cross_machine.py --peer PHRI_FASTDDS_PEER --phri PHRI --config RUN.yaml --out DIR
                   --mode multicast|unicast [--scenario interop|ft-touch] [--domain N]

multicast: phri with Cyclone's defaults (`--ros-discovery network`, no configuration file), the peer
           with Fast DDS's (multicast discovery): what two machines on one switch do.
unicast:   multicast switched off on the link (neither side could use it), phri with the peers
           configuration of docs/ros2.md (CYCLONEDDS_URI: its interface, AllowMulticast false, the
           other machine as peer) and the peer with unicast discovery to phri's address alone.

Needs root (network namespaces): otherwise it exits 77, which ctest reports as skipped.
"""
import argparse
import os
import subprocess
import sys

SKIP = 77
PHRI_ADDRESS, PEER_ADDRESS = "10.231.0.1", "10.231.0.2"


def ip(*args, check=True):
    return subprocess.run(["ip", *args], check=check, capture_output=True, text=True)


def counters(netns, dev):
    def read(name):
        out = subprocess.run(["ip", "netns", "exec", netns, "cat", f"/sys/class/net/{dev}/statistics/{name}"],
                             check=True, capture_output=True, text=True).stdout
        return int(out)
    return read("tx_packets"), read("rx_packets")


def cyclone_peers_xml(interface, peer):
    # The "Several machines" file of docs/ros2.md, multicast off (the link has none).
    return ('<CycloneDDS><Domain Id="any">'
            f'<General><Interfaces><NetworkInterface name="{interface}"/></Interfaces>'
            '<AllowMulticast>false</AllowMulticast></General>'
            '<Discovery><ParticipantIndex>auto</ParticipantIndex>'
            f'<Peers><Peer Address="{peer}"/></Peers></Discovery>'
            '</Domain></CycloneDDS>\n')


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--peer", required=True)
    ap.add_argument("--phri", required=True)
    ap.add_argument("--config", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--mode", choices=["multicast", "unicast"], required=True)
    ap.add_argument("--scenario", default="interop")
    ap.add_argument("--domain", type=int, default=48)
    a = ap.parse_args()

    if os.geteuid() != 0:
        print("SKIP: network namespaces need root")
        return SKIP
    tag = f"{os.getpid() % 100000}"
    ns_phri, ns_peer = f"phri_ctl{tag}", f"phri_rem{tag}"
    try:
        ip("netns", "add", ns_phri)
    except (OSError, subprocess.CalledProcessError) as e:
        print(f"SKIP: cannot make a network namespace here ({e})")
        return SKIP
    try:
        ip("netns", "add", ns_peer)
        # eth0 on both "machines", as docs/ros2.md's configuration names it.
        ip("link", "add", f"ve{tag}a", "type", "veth", "peer", "name", f"ve{tag}b")
        for end, ns, address in ((f"ve{tag}a", ns_phri, PHRI_ADDRESS), (f"ve{tag}b", ns_peer, PEER_ADDRESS)):
            ip("link", "set", end, "netns", ns)
            ip("-n", ns, "link", "set", end, "name", "eth0")
            ip("-n", ns, "addr", "add", f"{address}/24", "dev", "eth0")
            if a.mode == "unicast":
                ip("-n", ns, "link", "set", "eth0", "multicast", "off")
            ip("-n", ns, "link", "set", "eth0", "up")
            ip("-n", ns, "link", "set", "lo", "up")
            if a.mode == "multicast":  # a machine's default route would carry it; these have none
                ip("-n", ns, "route", "add", "224.0.0.0/4", "dev", "eth0")
        flags = ip("-n", ns_phri, "link", "show", "eth0").stdout
        print(f"link: phri {PHRI_ADDRESS} (netns {ns_phri}) <-> peer {PEER_ADDRESS} (netns {ns_peer}), "
              f"multicast {'on' if 'MULTICAST' in flags else 'off'}")

        env = dict(os.environ)
        env.pop("CYCLONEDDS_URI", None)
        env.pop("FASTRTPS_DEFAULT_PROFILES_FILE", None)
        os.makedirs(a.out, exist_ok=True)
        peer_args = ["--address", PEER_ADDRESS]
        if a.mode == "unicast":
            xml = os.path.join(a.out, "cyclonedds_peers.xml")
            with open(xml, "w") as f:
                f.write(cyclone_peers_xml("eth0", PEER_ADDRESS))
            env["CYCLONEDDS_URI"] = "file://" + os.path.abspath(xml)  # read by phri's Cyclone, not by Fast DDS
            peer_args += ["--unicast-peer", PHRI_ADDRESS]

        before = counters(ns_phri, "eth0")
        run = subprocess.run(["ip", "netns", "exec", ns_peer, a.peer, "--phri", a.phri, "--config", a.config,
                              "--out", a.out, "--domain", str(a.domain), "--scenario", a.scenario,
                              "--phri-netns", ns_phri, *peer_args], env=env, timeout=90)
        after = counters(ns_phri, "eth0")
        sent, received = after[0] - before[0], after[1] - before[1]
        # Hundreds of phri's messages went one way (joint states at 100 Hz, the rest at 50 Hz, for
        # seconds; a packet may carry several), the peer's targets, events or 500 Hz wrenches the other.
        crossed = sent > 300 and received > 100
        print(f"{'PASS' if crossed else 'FAIL'} the link carried it: phri's machine sent {sent} and received "
              f"{received} packets on eth0")
        return 0 if run.returncode == 0 and crossed else 1
    finally:
        for ns in (ns_phri, ns_peer):
            ip("netns", "del", ns, check=False)  # deleting a namespace deletes its end of the link


if __name__ == "__main__":
    sys.exit(main())
