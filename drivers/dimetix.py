"""Driver for Dimetix DLS / FLS laser distance sensors (ASCII protocol).

Protocol (DLS-A / DLS-C reference manuals): commands ``s<N><cmd>`` with N the device id 0-9 and
CR LF; a single distance ``sNg`` is answered ``gNg+xxxxxxxx`` in 0.1 mm, an error ``gN@Ezzz``.
Error codes are shared with the DISTO OEM family: E203 bad command, E222/E223/E224 interface
overflow/framing/buffer, E252/E254 temperature too high/low, E255 signal too weak, E256 too
strong, E257 too much background light. At power-up the device sends ``gN?``, which is skipped.

Keeping replies with their shots: the input is cleared before every ``sNg``; after a timeout
(or a reply that made no sense) the next measurement first sends ``sNc`` (stop) and reads up to
its ``gN?``, so a late answer to the earlier ``sNg`` is dropped instead of being taken for the
next shot's range. Only replies naming this device's id count; commands seen on the line (an
RS-485 adapter's echo, another host on the bus) are skipped.

Command line ending: the reference gives CR LF but not how the device splits it. The driver
sends CR LF; :meth:`DimetixDLS.probe` (two stops, ``sNc``) switches to CR alone for a device
that ends a command at CR and keeps the LF as the first byte of the next one (which it then
does not take for a command: the second stop goes unanswered), and to LF alone for one that
ends a command at LF and keeps the CR (which refuses or ignores even the first stop). An
ending is kept only when two stops are acknowledged with it.
"""

from __future__ import annotations

import re
import time

from asbuilt.errors import DeviceProtocolError, DeviceTimeout

from .rangefinder import (
    RangeFinderCommandError,
    RangeFinderError,
    SignalTooStrong,
    SignalTooWeak,
    TemperatureError,
    TooMuchBackgroundLight,
)
from .transport import LineChannel, open_port

__all__ = ["DimetixDLS", "DIMETIX_ERRORS"]

#: Error code -> (exception class, what it means, what to do).
DIMETIX_ERRORS = {
    203: (RangeFinderCommandError, "wrong command or parameter", "check the device id"),
    222: (RangeFinderCommandError, "interface overflow", "slow down the requests"),
    223: (RangeFinderCommandError, "framing error", "check baud rate and 7E1 line settings"),
    224: (RangeFinderCommandError, "buffer overflow", "slow down the requests"),
    252: (TemperatureError, "temperature too high", "let the device cool down"),
    254: (TemperatureError, "temperature too low", "warm the device up"),
    255: (SignalTooWeak, "received signal too weak", "aim at a surface or move closer"),
    256: (SignalTooStrong, "received signal too strong", "avoid reflectors; tilt the target"),
    257: (TooMuchBackgroundLight, "too much background light", "shade the target"),
}

_DISTANCE = re.compile(r"^g(\d)g([+-]\d{1,9})$")
_ERROR = re.compile(r"^g(\d)@E(\d{3})$")
_IDLE = re.compile(r"^g(\d)\?$")
_FROM = re.compile(r"^g(\d)")  # any reply names the id of the device that sent it

#: Seconds :meth:`DimetixDLS.laser` waits for a reply the reference does not promise.
LASER_REPLY_WAIT = 0.3
#: Seconds :meth:`DimetixDLS.probe` listens for an answer to a lone line ending it sends (to end
#: what the device holds of a command) before trying another ending.
FLUSH_WAIT = 0.3
_COMMAND = re.compile(r"^s\d", re.IGNORECASE)  # a command on the bus: an echo or another host's


class DimetixDLS:
    """A Dimetix DLS/FLS sensor on a serial port.

    Parameters
    ----------
    channel : LineChannel
        The open channel; use :meth:`open`.
    device_id : int
        N in the protocol, 0-9.
    """

    def __init__(self, channel: LineChannel, device_id: int = 0):
        if not 0 <= int(device_id) <= 9:
            raise ValueError(f"device_id must be 0-9, got {device_id}")
        self.channel = channel
        self.device_id = int(device_id)
        self._unsynced = False  # a reply may still be on its way (timeout, garbage)
        #: Command line ending: CR LF, or CR or LF alone once :meth:`probe` found that the device
        #: keeps the other byte as part of a command.
        self.eol = "\r\n"

    @classmethod
    def open(
        cls,
        url: str,
        *,
        device_id: int = 0,
        baudrate: int = 19200,
        bytesize: int = 7,
        parity: str = "E",
        timeout: float = 3.0,
    ) -> DimetixDLS:
        """Open the sensor at ``url`` (default 19200 baud 7E1, the common factory setting).

        With 7 data bits, bit 7 of every received byte is cleared: a pseudo-terminal, opened
        8N1 whatever is asked (:func:`~asbuilt.drivers.transport.open_port`), passes a 7E1
        device's even parity bit through as bit 7.
        """
        port = open_port(
            url, baudrate=baudrate, bytesize=bytesize, parity=parity, write_timeout=timeout
        )
        channel = LineChannel(
            port, f"Dimetix range finder on {url}", timeout, seven_bit=int(bytesize) == 7
        )
        return cls(channel, device_id)

    def __enter__(self) -> DimetixDLS:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Close the port."""
        self.channel.close()

    def _raise_code(self, code: int) -> None:
        cls, meaning, action = DIMETIX_ERRORS.get(
            code, (RangeFinderError, "unknown error", "see the device manual")
        )
        raise cls(f"{self.channel.name}: E{code:03d} {meaning}; {action}", code=f"E{code:03d}")

    def _line(self, what: str, timeout: float | None = None) -> str:
        """The next line from this device: echoed commands and other ids' replies skipped."""
        while True:
            line = self.channel.read_line(timeout, expecting=what)
            if _COMMAND.match(line):
                continue  # our own command echoed by a bus adapter, or another host's
            m = _FROM.match(line)
            if m and int(m.group(1)) != self.device_id:
                continue  # another device on the bus
            return line

    def measure(self, timeout: float | None = None) -> float:
        """One distance (``sNg``), metres.

        Parameters
        ----------
        timeout : float, optional
            Seconds to wait for the reply (default: the channel's).

        Returns
        -------
        float
            Range in metres (device value: 0.1 mm resolution, before calibration).

        Raises
        ------
        SignalTooWeak, SignalTooStrong, TooMuchBackgroundLight, TemperatureError,
        RangeFinderCommandError
            The device's error code.
        DeviceTimeout
            No reply within the timeout (the next call stops the device first).
        DeviceProtocolError
            A reply that is not ``gNg+xxxxxxxx``.
        """
        n = self.device_id
        if self._unsynced:
            self.stop()
        self.channel.discard_input()  # nothing received before the command can be its answer
        self.channel.write(f"s{n}g{self.eol}")
        try:
            while True:
                line = self._line(f"distance reply from device id {n}", timeout)
                if _IDLE.match(line):
                    continue  # power-up or stop acknowledgement
                m = _ERROR.match(line)
                if m:
                    self._raise_code(int(m.group(2)))
                m = _DISTANCE.match(line)
                if m is None:
                    raise DeviceProtocolError(
                        f"{self.channel.name}: unexpected reply {line!r} to s{n}g "
                        "(expected gNg+xxxxxxxx); check the baud rate, 7E1 and the device id"
                    )
                return int(m.group(2)) * 1e-4
        except (DeviceTimeout, DeviceProtocolError):
            self._unsynced = True
            raise

    def stop(self) -> None:
        """``sNc``: stop the current measurement and read up to its acknowledgement ``gN?``.

        Whatever the device sent before the acknowledgement (a late distance) is dropped.

        Raises
        ------
        DeviceTimeout
            No ``gN?`` from this device id within the timeout.
        """
        self.channel.discard_input()
        self.channel.write(f"s{self.device_id}c{self.eol}")
        while not _IDLE.match(self._line(f"stop acknowledgement from device id {self.device_id}")):
            pass  # a late reply to an earlier command
        self._unsynced = False

    def probe(self) -> None:
        """Check that the sensor answers on these line settings and settle how commands end:
        two stops (:meth:`stop`), both acknowledged.

        If one goes unanswered, the device may keep a byte of CR LF as part of a command: one
        that ends a command at CR and keeps the LF as the first byte of the next (the first
        stop answered, LF ``sNc`` not), or one that ends it at LF and keeps the CR (``sNc`` CR
        is no command: not even the first answered, or only refused, ``E203``). Each of CR and
        LF alone is then tried, the likelier first: a lone ending ends what the device holds
        of a command (its answer dropped), and two stops ended with it must be acknowledged.
        An ending that does not draw them is given up for CR LF again (:attr:`eol`), and the
        first timeout raised.

        Raises
        ------
        DeviceTimeout
            No acknowledgement with any of the endings tried.
        """
        answered = 0
        try:
            self.stop()
            answered = 1
            self.stop()
        except DeviceTimeout as exc:
            for eol in ("\r", "\n") if answered else ("\n", "\r"):
                if self._try_ending(eol):
                    return
            raise exc

    def _try_ending(self, eol: str) -> bool:
        """Send ``eol`` alone (ending what the device holds of a command, its answer dropped),
        then two stops ended with it; keep it if both are acknowledged, else go back to CR LF."""
        self.eol = eol
        self._flush()
        try:
            self.stop()
            self.stop()
            return True
        except DeviceTimeout:
            self.eol = "\r\n"
            self._flush()
            return False

    def _flush(self) -> None:
        """Send :attr:`eol` alone and drop whatever comes within ``FLUSH_WAIT`` of quiet."""
        self.channel.discard_input()
        self.channel.write(self.eol)
        deadline = time.monotonic() + self.channel.timeout
        while time.monotonic() < deadline:
            try:
                self.channel.read_line(FLUSH_WAIT)
            except DeviceTimeout:
                break
            except DeviceProtocolError:
                continue
        self.channel.discard_input()
        self._unsynced = False

    def laser(self, on: bool) -> None:
        """``sNo`` / ``sNp``: laser pointer on or off.

        The reference gives the reply of ``sNc`` (``gN?``) but none for these: an
        acknowledgement ``gN?`` or silence for ``LASER_REPLY_WAIT`` seconds are both taken as
        done; an error reply raises as a measurement's does.
        """
        self.channel.discard_input()
        self.channel.write(f"s{self.device_id}{'o' if on else 'p'}{self.eol}")
        try:
            line = self._line("acknowledgement", LASER_REPLY_WAIT)
        except DeviceTimeout:
            return
        m = _ERROR.match(line)
        if m:
            self._raise_code(int(m.group(2)))
        if not _IDLE.match(line):
            raise DeviceProtocolError(f"{self.channel.name}: unexpected reply {line!r} to laser")
