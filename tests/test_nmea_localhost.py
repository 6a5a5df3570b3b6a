"""Issue 38: ``--nmea-udp localhost:P`` where the resolver lists ``::1`` before ``127.0.0.1`` (an
/etc/hosts so ordered; nodejs/node#40702): the sender used the first address only, and an IPv4
listener heard nothing, with no note. It now sends every sentence to every address the host
resolves to and says so in one line. Loopback only; the resolver's order is the test's
(socket.getaddrinfo replaced), not this machine's."""

import socket

import pynmea2
import pytest

from gyro_instrument.recording.nmea import NmeaUdpSender, resolve_udp_targets, targets_note


def _ipv6_first(real):
    """getaddrinfo answering 'localhost' with ::1 first, then 127.0.0.1 (the order of the report)."""
    def fake(host, port, *args, **kwargs):
        if host != "localhost":
            return real(host, port, *args, **kwargs)
        return [(socket.AF_INET6, socket.SOCK_DGRAM, 17, "", ("::1", port, 0, 0)),
                (socket.AF_INET, socket.SOCK_DGRAM, 17, "", ("127.0.0.1", port)),
                (socket.AF_INET, socket.SOCK_DGRAM, 17, "", ("127.0.0.1", port))]   # a repeat, as some resolvers give
    return fake


@pytest.fixture
def listener():
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.settimeout(10.0)          # a bound on a lost datagram, not a timing: loopback delivers at once
    yield sock
    sock.close()


def test_an_ipv4_listener_hears_localhost_when_ipv6_resolves_first(listener, monkeypatch):
    monkeypatch.setattr(socket, "getaddrinfo", _ipv6_first(socket.getaddrinfo))
    port = listener.getsockname()[1]
    with NmeaUdpSender(f"localhost:{port}") as tx:
        assert [f for f, _ in tx.targets] == [socket.AF_INET6, socket.AF_INET]    # both, repeat dropped
        assert tx.note == (f"localhost:{port} resolves to 2 addresses: each NMEA sentence goes to every one "
                           f"([::1]:{port}, 127.0.0.1:{port})")
        sentence = tx.send_heading(123.4567, 3)
    data, _ = listener.recvfrom(100)
    msg = pynmea2.parse(data.decode("ascii").strip(), check=True)   # an independent parser reads what arrived
    assert data.decode("ascii") == sentence + "\r\n" and float(msg.heading) == 123.457


def test_one_address_is_one_target_without_a_note(listener):
    port = listener.getsockname()[1]
    targets = resolve_udp_targets(f"127.0.0.1:{port}")
    assert targets == [(socket.AF_INET, ("127.0.0.1", port))] and targets_note("x", targets) is None
    with NmeaUdpSender(f"127.0.0.1:{port}") as tx:
        assert tx.note is None
        tx.send_heading(1.0)
    data = listener.recvfrom(100)[0].decode("ascii")
    # pynmea2 checks the checksum itself (check=True): an independent reading of the datagram
    assert data.endswith("\r\n") and float(pynmea2.parse(data.strip(), check=True).heading) == 1.0


def test_an_address_that_refuses_does_not_stop_the_others(listener, monkeypatch):
    # the IPv6 socket's sendto fails (a machine without IPv6): the IPv4 listener still hears it
    monkeypatch.setattr(socket, "getaddrinfo", _ipv6_first(socket.getaddrinfo))
    port = listener.getsockname()[1]
    with NmeaUdpSender(f"localhost:{port}") as tx:
        class Refusing:
            def sendto(self, *a):
                raise OSError(101, "Network is unreachable")

            def close(self):
                pass
        tx._socks[socket.AF_INET6].close()
        tx._socks[socket.AF_INET6] = Refusing()
        tx.send_heading(2.0)
    assert float(pynmea2.parse(listener.recvfrom(100)[0].decode("ascii").strip(), check=True).heading) == 2.0
