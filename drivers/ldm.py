"""Driver for Jenoptik / ASTECH LDM41 and LDM42 laser distance meters (ASCII protocol).

Protocol (LDM41 / LDM42 operating manuals): 8N1, default 9600 baud; ``DM`` measures once.
A distance comes back in the selected output format: d ``004.996`` (metres at scale 1), s
``004.996 000985`` (with the signal quality 0-1024) or h (hexadecimal millimetres, e.g.
``001388``); an error as ``Exx`` CR LF, e.g. ``E15`` (poor reflectance or too short a
measuring time). The driver reads all three formats, at scale factor 1 (``SF``), the factory
setting. A reply of ``E`` and exactly two digits is an error code (the manual's ``Exx``); any
other hexadecimal reply (``E9``, ``E100``, ``000E10``) is a distance. An unpadded hexadecimal
distance can still look like an error (3600 mm is ``E10``), so :meth:`LDM4x.probe` sets format
d (``SDd``) when the meter's answer is not a decimal distance. Only E15's meaning is
documented in the reference used here; other codes are reported as the device sent them.

Command line ending: the reference shows the replies' (CR LF) but not the commands'. The
driver sends CR LF; :meth:`LDM4x.probe` switches to CR alone for a meter that ends a command at
CR and again at LF (it answers the empty second one too, an ``Exx`` before or after the
distance), for one that ends it at CR and keeps the LF as the start of the next command (which
it then refuses: a second ``DM`` at the same aim answered with an error), and to LF alone for one
that ends it at LF and keeps the CR in it (which refuses even the first ``DM``: an error other
than E15, or silence).

Keeping replies with their shots: the input is cleared before every ``DM`` (a power-up
autostart line, a stale answer); the protocol has no stop command, so after a timeout the next
measurement first waits (up to its timeout) for the late answer and drops it.
"""

from __future__ import annotations

import re
import time

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
_HEX_MM = re.compile(r"^[0-9A-Fa-f]+$")
_ERROR = re.compile(r"^E(\d{2})$")  # the manual's "Exx": exactly two digits

#: Seconds :meth:`LDM4x.probe` listens, after a distance, for a second reply to its one ``DM``
#: (the empty command after CR answered at once).
SECOND_REPLY_WAIT = 0.3


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
        self._last_reply = ""  # the last DM's reply line, as sent
        #: Command line ending: CR LF, or CR or LF alone once :meth:`probe` found that the meter
        #: needs it.
        self.eol = "\r\n"

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
        self.channel.write("DM" + self.eol)
        try:
            line = self._line("distance reply", timeout)
        except DeviceTimeout:
            self._late = True
            raise
        return self._distance(line)

    def _distance(self, line: str) -> float:
        """The distance in metres a reply line holds; raises as :meth:`measure` does."""
        self._last_reply = line
        m = _ERROR.match(line)
        if m:
            code = int(m.group(1))
            cls, meaning, action = LDM_ERRORS.get(
                code, (RangeFinderError, "device error", "see the LDM manual for this code")
            )
            raise cls(f"{self.channel.name}: E{code:02d} {meaning}; {action}", code=f"E{code:02d}")
        m = _DISTANCE.match(line)
        if m is not None:
            self.last_quality = int(m.group(2)) if m.group(2) else None
            return float(m.group(1))
        if _HEX_MM.match(line):
            self.last_quality = None
            return int(line, 16) / 1000.0
        raise DeviceProtocolError(
            f"{self.channel.name}: unexpected reply {line!r} to DM (expected a distance such as "
            "004.996, 004.996 000985 or hexadecimal millimetres, or Exx); check the baud rate"
        )

    def probe(self) -> None:
        """Check that the meter answers on these line settings, settle how commands end and make
        sure distances come back in decimal (the reference lists no query without a
        measurement, so every check is a ``DM``; an error code is an answer too).

        1. One ``DM`` CR LF. A second reply to it means the meter ended the command at CR and
           again at LF: an error first (the empty command's, answered at once) is followed by
           the distance within the reply timeout; a distance first by the error within
           ``SECOND_REPLY_WAIT``. Commands then end with CR alone (:attr:`eol`). Silence, or
           one error other than E15 (the miss), may be a meter that ends a command at LF and
           keeps the CR in it (``DM`` CR is no command): two ``DM`` LF answered alike with a
           distance or E15 make commands end with LF alone (else the driver goes back to CR LF,
           and silence raises the first timeout).
        2. Otherwise a second ``DM`` CR LF at the same aim must be answered in kind (a distance
           after a distance, the same code after a code). A meter that ends a command at CR
           and keeps the LF as the first byte of the next command refuses that second one (an
           error after a distance, another code, or silence): a lone CR then ends the stray LF's
           command, its answer is dropped, and two ``DM`` CR must be answered in kind, else
           the driver goes back to CR LF.
        3. A reply that is not a decimal distance (format h, or an error code, which at format h
           can also be a hexadecimal distance such as ``E10``) makes the driver set format d
           (``SDd``, its acknowledgement read and dropped) and measure once more. A meter
           already at format d or s is left as it is.

        Raises
        ------
        DeviceTimeout, DeviceProtocolError
            Silence, or a reply that is neither a distance nor ``Exx`` (wrong baud rate).
        """
        try:
            first = self._answer()
        except DeviceTimeout as exc:  # silence: maybe "DM" CR is no command for this meter
            last = self._try_lf()
            if last is None:
                raise exc
            if not _decimal(last):
                self._set_decimal()
            return
        # after an error, the distance may follow the empty command's error: the full timeout
        wait = SECOND_REPLY_WAIT if _kind(first) == "distance" else None
        try:
            second = self._line("second reply", wait)
        except DeviceTimeout:
            second = None
        if second is not None:
            if _ERROR.match(second) is None:
                self._distance(second)  # anything else is the baud rate's problem, said as such
            self.eol = "\r"
            last = self._answer()
        elif _refused(first) and (lf := self._try_lf()) is not None:
            last = lf
        else:
            try:
                last = self._answer()
            except DeviceTimeout:  # a meter that stays silent for a command it does not know
                last = None
            if _kind(last) != _kind(first):
                last = self._try_cr(first, last)
        if not _decimal(last):
            self._set_decimal()

    def _answer(self) -> str:
        """One ``DM``'s reply line as sent (a distance or ``Exx``), checked but not converted."""
        try:
            self.measure()
        except RangeFinderError as exc:
            return exc.code
        return self._last_reply

    def _try_cr(self, first: str, second: str | None) -> str:
        """Commands ended with CR LF drew replies of different kinds (``first``, ``second``;
        None for silence): try CR alone (see :meth:`probe`, step 2); the last reply of the
        ending kept."""
        self._late = False  # the flush waits for, and drops, anything still owed
        a, b = self._two_answers("\r")
        if (
            a is not None
            and _kind(a) == _kind(b)
            and (_kind(first) == "distance" or _kind(a) != _kind(second))
        ):
            return b
        self._late = False
        self._flush("\r\n")
        self.eol = "\r\n"
        return self._answer()

    def _try_lf(self) -> str | None:
        """``DM`` CR LF drew silence or a refusal: try LF alone (see :meth:`probe`, step 1); the
        last reply if two ``DM`` LF are answered alike with a distance or E15, else None (CR LF
        again)."""
        self._late = False  # a meter that refused "DM" CR owes no answer to it
        a, b = self._two_answers("\n")
        if a is not None and _kind(a) == _kind(b) and not _refused(a):
            return b
        self._late = False
        self._flush("\r\n")
        self.eol = "\r\n"
        return None

    def _two_answers(self, ending: str) -> tuple[str | None, str | None]:
        """Commands ended with ``ending`` from now on (after :meth:`_flush`): the replies to two
        ``DM``, or (None, None) when either met silence."""
        self._flush(ending)
        self.eol = ending
        try:
            return self._answer(), self._answer()
        except DeviceTimeout:
            return None, None

    def _flush(self, ending: str) -> None:
        """Send ``ending`` alone (it ends whatever the meter holds of a command) and drop the
        answer it may draw."""
        self.channel.write(ending)
        deadline = time.monotonic() + self.channel.timeout  # a meter streaming (autostart)
        try:
            while time.monotonic() < deadline:
                self.channel.read_line(SECOND_REPLY_WAIT)
        except DeviceTimeout:
            pass
        self.channel.discard_input()

    def _set_decimal(self) -> None:
        """``SDd``: output format d (see :meth:`probe`, step 3), then one ``DM``."""
        self.channel.discard_input()
        self.channel.write("SDd" + self.eol)
        try:  # the reference gives no acknowledgement: one line or silence, dropped
            self.channel.read_line(SECOND_REPLY_WAIT)
        except DeviceTimeout:
            pass
        self.channel.discard_input()
        self._answer()


def _kind(reply: str | None) -> str | None:
    """``"distance"`` or the error code: what two answers at the same aim share."""
    if reply is None:
        return None
    return reply if _ERROR.match(reply) else "distance"


def _refused(reply: str) -> bool:
    """Whether ``reply`` is an error code other than E15 (the miss): what a meter may answer to
    a command it does not know."""
    return _kind(reply) not in ("distance", "E15")


def _decimal(reply: str) -> bool:
    """Whether ``reply`` is a decimal distance (format d or s)."""
    return _DISTANCE.match(reply) is not None
