"""Driver for Jenoptik / ASTECH LDM41 and LDM42 laser distance meters (ASCII protocol).

Protocol (LDM41 / LDM42 operating manuals): 8N1, default 9600 baud; ``DM`` CR LF measures once.
A distance comes back in the selected output format: d ``004.996`` (metres at scale 1) or s
``004.996 000985`` (with the signal quality 0-1024); an error as ``Exx`` CR LF, e.g. ``E15``
(poor reflectance or too short a measuring time). The driver expects the decimal formats d or
s at scale factor 1 (``SF``), the factory setting; any other reply is a protocol error that
says so. Only E15's meaning is documented in the reference used here; other codes are reported
as the device sent them.

Keeping replies with their shots: the input is cleared before every ``DM`` (a power-up
autostart line, a stale answer); the protocol has no stop command, so after a timeout the next
measurement first waits (up to its timeout) for the late answer and drops it.
"""

from __future__ import annotations

import re

from asbuilt.errors import DeviceProtocolError, DeviceTimeout

from .rangefinder import RangeFinderError, SignalTooWeak
from .transport import LineChannel, open_port

__all__ = ["LDM4x", "LDM_ERRORS"]

#: Error code -> (exception class, what it means, what to do), for the codes whose meaning
#: the reference gives (docs/drivers.md); any other ``Exx`` is reported as the device's code.
LDM_ERRORS = {
    15: (
        SignalTooWeak,
        "poor reflectance or too short a measuring time",
        "aim at a brighter surface or raise the measuring time (ST)",
    ),
}

_DISTANCE = re.compile(r"^([+-]?\d+\.\d+)(?:\s+(\d+))?$")
_ERROR = re.compile(r"^E(\d{1,3})$")


class LDM4x:
    """A Jenoptik LDM41/42 on a serial port.

    Parameters
    ----------
    channel : LineChannel
        The open channel; use :meth:`open`.
    """

    def __init__(self, channel: LineChannel):
        self.channel = channel
        self.last_quality: int | None = None
        self._late = False  # a DM timed out: its answer may still come

    @classmethod
    def open(cls, url: str, *, baudrate: int = 9600, timeout: float = 3.0) -> LDM4x:
        """Open the meter at ``url`` (8N1, default 9600 baud)."""
        port = open_port(url, baudrate=baudrate, write_timeout=timeout)
        return cls(LineChannel(port, f"LDM range finder on {url}", timeout))

    def __enter__(self) -> LDM4x:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Close the port."""
        self.channel.close()

    def _line(self, what: str, timeout: float | None) -> str:
        """The next line that is not our own command echoed back."""
        while True:
            line = self.channel.read_line(timeout, expecting=what)
            if line.upper().startswith("DM"):
                line = line[2:].strip()
            if line:
                return line

    def measure(self, timeout: float | None = None) -> float:
        """One distance (``DM``), metres; :attr:`last_quality` keeps the signal quality if sent.

        Parameters
        ----------
        timeout : float, optional
            Seconds to wait for the reply (default: the channel's).

        Raises
        ------
        SignalTooWeak
            E15.
        RangeFinderError
            Any other ``Exx`` (its code kept).
        DeviceTimeout, DeviceProtocolError
            Silence or an unparseable reply.
        """
        if self._late:
            self._late = False
            try:
                self._line("late distance reply", timeout)
            except DeviceTimeout:
                pass  # the device dropped it
        self.channel.discard_input()
        self.channel.write("DM\r\n")
        try:
            line = self._line("distance reply", timeout)
        except DeviceTimeout:
            self._late = True
            raise
        m = _ERROR.match(line)
        if m:
            code = int(m.group(1))
            cls, meaning, action = LDM_ERRORS.get(
                code, (RangeFinderError, "device error", "see the LDM manual for this code")
            )
            raise cls(f"{self.channel.name}: E{code:02d} {meaning}; {action}", code=f"E{code:02d}")
        m = _DISTANCE.match(line)
        if m is None:
            raise DeviceProtocolError(
                f"{self.channel.name}: unexpected reply {line!r} to DM (expected e.g. 004.996); "
                "set output format d or s and scale 1, check the baud rate"
            )
        self.last_quality = int(m.group(2)) if m.group(2) else None
        return float(m.group(1))

    def probe(self) -> None:
        """Check that the meter answers on these line settings: one ``DM`` (an error code is an
        answer too; the reference lists no query without a measurement).

        Raises
        ------
        DeviceTimeout, DeviceProtocolError
            Silence, or a reply that is neither a distance nor ``Exx`` (wrong baud rate).
        """
        try:
            self.measure()
        except RangeFinderError:
            pass
