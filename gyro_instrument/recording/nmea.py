"""NMEA 0183 true heading (``$HEHDT``) sentences, and a UDP sender for them (pure Python).

Sentence (NMEA 0183 HDT, "Heading – True"; talker ``HE`` = heading, north-seeking gyro)::

    $HEHDT,<heading>,T*<hh><CR><LF>

- ``<heading>``: degrees clockwise from true north, in [0, 360), written with a fixed number of
  decimals (default 1, i.e. 0.1°, as gyrocompasses commonly send it; up to 6). The value is
  rounded first and wrapped after, so 359.96 at one decimal is ``0.0``, never ``360.0``.
- ``<hh>``: the checksum, the XOR of every character between ``$`` and ``*`` (both excluded), as
  two upper-case hexadecimal digits.
- A sentence is at most 82 characters including ``$`` and ``<CR><LF>``; 6 decimals give 24.

:func:`hehdt_sentence` returns the sentence without ``<CR><LF>``; :class:`NmeaUdpSender` sends each
sentence as one UDP datagram ending in ``<CR><LF>`` (the usual framing of NMEA over plain UDP,
as chart plotters listening on a UDP port take it). The sender takes any HOST:PORT a user gives
(IANA assigns port 10110 to ``nmea-0183``); tests, CI and demos send to loopback only.

One decimal (0.1° = 360″) is coarser than a converged gyrocompass estimate (arcseconds): a caller
that wants the estimate's resolution asks for 3 (3.6″) or 4 decimals.
"""

import math
import socket

from gyro_instrument.core.errors import SceneError

#: the IANA port registered for NMEA 0183 over UDP/TCP ("nmea-0183", 10110)
NMEA_UDP_PORT = 10110
#: most decimals written for the heading (1e-6 deg = 3.6 mas, beyond any estimate here)
MAX_DECIMALS = 6
#: longest NMEA 0183 sentence, "$" through <CR><LF> included
MAX_SENTENCE_CHARS = 82

_VALID_TARGET = (f"HOST:PORT with PORT an integer in [1, 65535] and HOST a name or address that resolves, "
                 f"e.g. 127.0.0.1:{NMEA_UDP_PORT} (IPv6: [::1]:{NMEA_UDP_PORT})")


def nmea_checksum(body: str) -> str:
    """NMEA 0183 checksum of ``body`` (the characters between ``$`` and ``*``): their XOR as two
    upper-case hexadecimal digits."""
    x = 0
    for ch in body:
        x ^= ord(ch)
    return f"{x:02X}"


def format_heading(heading_deg: float, decimals: int = 1) -> str:
    """``heading_deg`` wrapped to [0, 360) and written with ``decimals`` decimals (rounded, then
    wrapped: never ``360.0``).

    Raises
    ------
    SceneError
        A non-finite heading, or ``decimals`` not an integer in [0, MAX_DECIMALS].
    """
    if isinstance(decimals, bool) or not isinstance(decimals, int) or not 0 <= decimals <= MAX_DECIMALS:
        raise SceneError("nmea.decimals", decimals, f"must be an integer in [0, {MAX_DECIMALS}]")
    try:
        h = float(heading_deg)
    except (TypeError, ValueError):
        h = math.nan
    if not math.isfinite(h):
        raise SceneError("nmea.heading_deg", heading_deg, "must be a finite number of degrees")
    text = f"{h % 360.0:.{decimals}f}"
    if float(text) >= 360.0:
        text = f"{0.0:.{decimals}f}"
    return text


def hehdt_sentence(heading_deg: float, decimals: int = 1) -> str:
    """``$HEHDT,<heading>,T*hh``: the true heading ``heading_deg`` (degrees clockwise from true
    north, any finite value, wrapped to [0, 360)) with ``decimals`` decimals and its checksum;
    no ``<CR><LF>``. Example: ``hehdt_sentence(123.4)`` → ``'$HEHDT,123.4,T*2B'``."""
    body = f"HEHDT,{format_heading(heading_deg, decimals)},T"
    return f"${body}*{nmea_checksum(body)}"


def parse_udp_target(text: str, field: str = "--nmea-udp") -> tuple:
    """Split and check ``HOST:PORT`` (``[IPV6]:PORT`` for IPv6 literals).

    Returns
    -------
    (host, port) : (str, int)

    Raises
    ------
    SceneError
        Naming ``field``, the value and the valid form, when the text is not HOST:PORT or the port
        is not an integer in [1, 65535].
    """
    if not isinstance(text, str):
        raise SceneError(field, text, _VALID_TARGET)
    host, sep, port_text = text.strip().rpartition(":")
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    elif ":" in host:
        raise SceneError(field, text, _VALID_TARGET + "; an IPv6 address goes in brackets")
    if not sep or not host:
        raise SceneError(field, text, _VALID_TARGET)
    if not (port_text.isascii() and port_text.isdigit()):
        raise SceneError(field, text, f"{_VALID_TARGET}; the PORT {port_text!r} is not an integer")
    port = int(port_text)
    if not 1 <= port <= 65535:
        raise SceneError(field, text, f"{_VALID_TARGET}; the PORT {port} is outside [1, 65535]")
    return host, port


def resolve_udp_target(text: str, field: str = "--nmea-udp") -> tuple:
    """:func:`parse_udp_target`, then resolve the host for UDP: ``(family, sockaddr)`` of the
    first address ``socket.getaddrinfo`` gives; SceneError naming ``field`` when it gives none."""
    return resolve_udp_targets(text, field)[0]


def resolve_udp_targets(text: str, field: str = "--nmea-udp") -> list:
    """Every address the host of ``text`` resolves to for UDP, ``[(family, sockaddr), ...]`` in
    ``socket.getaddrinfo``'s order without repeats. ``localhost`` is ``::1`` and ``127.0.0.1`` on
    many machines, in either order (``/etc/hosts``): a listener on one hears only what is sent to
    it, so :class:`NmeaUdpSender` sends to all of them (issue 38; nodejs/node#40702).

    Raises
    ------
    SceneError
        Naming ``field``: not HOST:PORT (:func:`parse_udp_target`) or the host does not resolve.
    """
    host, port = parse_udp_target(text, field)
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_DGRAM)
    except (socket.gaierror, UnicodeError) as err:
        raise SceneError(field, text, f"{_VALID_TARGET}; the HOST {host!r} does not resolve ({err})") from None
    out = []
    for family, _, _, _, sockaddr in infos:
        if family in (socket.AF_INET, socket.AF_INET6) and (family, sockaddr) not in out:
            out.append((family, sockaddr))
    if not out:
        raise SceneError(field, text, f"{_VALID_TARGET}; the HOST {host!r} resolves to no IPv4 or IPv6 address")
    return out


def targets_note(text: str, targets: list) -> str | None:
    """One line saying that ``text`` is sent to several addresses (None when it is one)."""
    if len(targets) < 2:
        return None
    shown = ", ".join(f"[{a[0]}]:{a[1]}" if f == socket.AF_INET6 else f"{a[0]}:{a[1]}" for f, a in targets)
    return f"{text} resolves to {len(targets)} addresses: each NMEA sentence goes to every one ({shown})"


class NmeaUdpSender:
    """Sends NMEA 0183 sentences as UDP datagrams to one HOST:PORT (to every address its host
    resolves to: :func:`resolve_udp_targets`).

    Parameters
    ----------
    target : str
        ``HOST:PORT`` (``[IPV6]:PORT``), checked and resolved once, here.
    field : str
        The option or parameter the target came from, named in errors (default ``--nmea-udp``).

    Notes
    -----
    One sentence per datagram, ending in ``<CR><LF>``. The socket is unconnected (``sendto``), so
    nobody listening is not an error; IPv4 sockets may send to a broadcast address. Use as a
    context manager or call :meth:`close`. Sending raises ``OSError`` if the network refuses it
    at every address.
    """

    def __init__(self, target: str, field: str = "--nmea-udp") -> None:
        self.target = target
        #: every (family, sockaddr) the target resolves to (:func:`resolve_udp_targets`), and the
        #: note saying so when there are several (None for one)
        self.targets = resolve_udp_targets(target, field)
        self.note = targets_note(target, self.targets)
        self.family, self.address = self.targets[0]
        self._socks = {}
        for family in dict.fromkeys(f for f, _ in self.targets):
            self._socks[family] = socket.socket(family, socket.SOCK_DGRAM)
            if family == socket.AF_INET:
                self._socks[family].setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)

    def send(self, sentence: str) -> int:
        """Send one sentence (``<CR><LF>`` appended when missing); returns the bytes sent.

        Raises
        ------
        SceneError
            Not an ASCII sentence starting with ``$`` or ``!``, or longer than 82 characters.
        """
        line = sentence if sentence.endswith("\r\n") else sentence + "\r\n"
        if (not line.startswith(("$", "!")) or not line.isascii() or len(line) > MAX_SENTENCE_CHARS
                or "\r\n" in line[:-2]):
            raise SceneError("nmea.sentence", sentence,
                             f"must be one ASCII NMEA 0183 sentence starting with '$' or '!', "
                             f"at most {MAX_SENTENCE_CHARS} characters with <CR><LF>")
        data = line.encode("ascii")
        sent, errors = 0, []
        for family, address in self.targets:
            try:
                sent = self._socks[family].sendto(data, address)
            except OSError as exc:       # e.g. no IPv6 on this machine: the other addresses still get it
                errors.append(exc)
        if len(errors) == len(self.targets):
            raise errors[0]
        return sent

    def send_heading(self, heading_deg: float, decimals: int = 1) -> str:
        """Send ``$HEHDT`` for ``heading_deg`` (:func:`hehdt_sentence`); returns the sentence."""
        sentence = hehdt_sentence(heading_deg, decimals)
        self.send(sentence)
        return sentence

    def close(self) -> None:
        """Close the sockets (idempotent)."""
        for sock in self._socks.values():
            sock.close()

    def __enter__(self) -> "NmeaUdpSender":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
