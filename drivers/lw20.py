"""Driver for LightWare LW20 / SF20 laser range finders in serial mode.

Protocol (/work/shared/reference/protocols.md, "LightWare LW20 / SF20"): 115200 baud; ``www``
CR LF selects serial mode, then ``LD`` CR LF returns the distance in metres as text.

What the reference leaves open and this driver assumes (docs/drivers.md):

* ``www`` is sent once, when the port is opened; whatever the device answers to it (nothing, a
  banner, an acknowledgement) is read and dropped until the line has been quiet for
  ``WWW_SETTLE`` seconds (at most the reply timeout), and the input is cleared before every
  ``LD``. An answer to ``www`` slower than that can still be the first line after the probe's
  ``LD``: the probe then measures once more;
* the reply is one line holding a decimal number of metres, maybe with whitespace around it,
  a label before it (``ld:``, ``LD ``, ``ldf,0:``: letters, an optional ``,N``, then ``:``,
  ``=`` or a space) and a unit ``m`` after it. Anything else (no number, two numbers, stray
  text) is a :class:`~asbuilt.errors.DeviceProtocolError`: a wrong baud rate or not an LW20;
* a value of zero or below (``0.00``, ``-1.00``) is the device's "no target" and raises
  :class:`~asbuilt.drivers.rangefinder.SignalTooWeak` (code ``no-target``), a miss like the
  other finders' "signal too weak"; so does a "no target" said in text: ``no target`` (any case,
  also ``no-target``, ``notarget``) or dashes in place of the number (``--.--``, ``----``),
  with the same optional label and unit. Any other text stays a protocol error;
* a line that is only our own command echoed back (``LD``, ``www``) is skipped.

Keeping replies with their shots: the protocol has no stop command, so after a timeout the next
measurement first waits (up to its timeout) for the late answer and drops it, as
:class:`~asbuilt.drivers.ldm.LDM4x` does.
"""

from __future__ import annotations

import math
import re
import time

from asbuilt.errors import DeviceProtocolError, DeviceTimeout

from .rangefinder import SignalTooWeak
from .transport import LineChannel, open_port

__all__ = ["LW20", "parse_distance"]

_REPLY = re.compile(
    r"^(?:[A-Za-z]+(?:,\d+)?\s*[:=]\s*|[A-Za-z]+\s+)?"  # an optional label: ld: / LD / ldf,0:
    r"([-+]?(?:\d+(?:\.\d*)?|\.\d+))"  # the number of metres
    r"\s*(?:m)?$"  # an optional unit
)
_NO_TARGET = re.compile(
    r"^(?:[A-Za-z]+(?:,\d+)?\s*[:=]\s*|[A-Za-z]+\s+)?"  # the same optional label
    r"(?:no[\s_-]*target|--+(?:\.-+)?|-\.-+)"  # "no target" in words, dashes for the number
    r"\s*(?:m)?$",
    re.IGNORECASE,
)
_ECHO = re.compile(r"^(?:LD|www)$", re.IGNORECASE)

#: Seconds of quiet after ``www`` taken as the end of the device's answer to it (if any).
WWW_SETTLE = 0.2


def parse_distance(line: str, name: str = "LW20") -> float:
    """The distance in metres a reply line holds.

    Raises
    ------
    SignalTooWeak
        The value is 0 or negative, or the line says "no target" in text (``no target``,
        ``--.--``): no target.
    DeviceProtocolError
        The line is not one number (with an optional label and unit).
    """
    text = line.strip()
    m = _REPLY.match(text)
    value = float(m.group(1)) if m else math.nan
    if m is None and _NO_TARGET.match(text):
        value = 0.0  # no target, said in text
    if not math.isfinite(value):
        raise DeviceProtocolError(
            f"{name}: unexpected reply {line!r} to LD (expected a distance in metres such as "
            "4.99); check the baud rate (115200) and that this is an LW20 / SF20"
        )
    if value <= 0:
        raise SignalTooWeak(
            f"{name}: no target (the device answered {text!r}); aim at a surface or move closer",
            code="no-target",
        )
    return value


class LW20:
    """A LightWare LW20 / SF20 on a serial port.

    Parameters
    ----------
    channel : LineChannel
        The open channel; use :meth:`open` (which also selects serial mode).
    """

    def __init__(self, channel: LineChannel):
        self.channel = channel
        self._late = False  # an LD timed out: its answer may still come

    @classmethod
    def open(
        cls, url: str, *, baudrate: int = 115200, timeout: float = 3.0, select: bool = True
    ) -> LW20:
        """Open the device at ``url`` (8N1, default 115200 baud); send ``www`` unless ``select``
        is False."""
        port = open_port(url, baudrate=baudrate, write_timeout=timeout)
        lrf = cls(LineChannel(port, f"LW20 range finder on {url}", timeout))
        if select:
            try:
                lrf.select_serial_mode()
            except BaseException:
                lrf.close()
                raise
        return lrf

    def __enter__(self) -> LW20:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Close the port."""
        self.channel.close()

    def select_serial_mode(self) -> None:
        """``www``: put the device in serial mode; what it answers (the reference gives no
        answer; a banner or an acknowledgement line) is dropped until the line has been quiet
        for ``WWW_SETTLE`` seconds, at most the channel's timeout (see the module docs)."""
        self.channel.write("www\r\n")
        deadline = time.monotonic() + self.channel.timeout
        while (left := deadline - time.monotonic()) > 0:
            try:
                self.channel.read_line(min(WWW_SETTLE, left), expecting="answer to www")
            except (DeviceTimeout, DeviceProtocolError):
                break
        self.channel.discard_input()

    def _line(self, what: str, timeout: float | None) -> str:
        """The next line that is not our own command echoed back."""
        while True:
            line = self.channel.read_line(timeout, expecting=what)
            if not _ECHO.match(line):
                return line

    def measure(self, timeout: float | None = None) -> float:
        """One distance (``LD``), metres.

        Raises
        ------
        SignalTooWeak
            No target (a value <= 0, ``no target``, ``--.--``).
        DeviceTimeout, DeviceProtocolError
            Silence or a reply that is not a distance.
        """
        if self._late:
            self._late = False
            try:
                self._line("late distance reply", timeout)
            except DeviceTimeout:
                pass  # the device dropped it
        self.channel.discard_input()
        self.channel.write("LD\r\n")
        try:
            line = self._line("distance reply to LD", timeout)
        except DeviceTimeout:
            self._late = True
            raise
        return parse_distance(line, self.channel.name)

    def probe(self) -> None:
        """Check that the device answers on these line settings: one ``LD`` (no target counts
        as an answer). A first reply that is no distance may be a late answer to ``www``: one
        more ``LD`` must then be answered with a distance."""
        try:
            try:
                self.measure()
            except DeviceProtocolError:
                self.measure()
        except SignalTooWeak:
            pass
