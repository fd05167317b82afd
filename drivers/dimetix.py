"""Driver for Dimetix DLS / FLS laser distance sensors (ASCII protocol).

Protocol (DLS-A / DLS-C reference manuals): commands ``s<N><cmd>`` with N the device id 0-9 and
CR LF; a single distance ``sNg`` is answered ``gNg+xxxxxxxx`` in 0.1 mm, an error ``gN@Ezzz``.
Error codes are shared with the DISTO OEM family: E203 bad command, E222/E223/E224 interface
overflow/framing/buffer, E252/E254 temperature too high/low, E255 signal too weak, E256 too
strong, E257 too much background light. At power-up the device sends ``gN?``, which is skipped.
"""

from __future__ import annotations

import re

from asbuilt.errors import DeviceProtocolError

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
        """Open the sensor at ``url`` (default 19200 baud 7E1, the common factory setting)."""
        port = open_port(
            url, baudrate=baudrate, bytesize=bytesize, parity=parity, write_timeout=timeout
        )
        return cls(LineChannel(port, f"Dimetix range finder on {url}", timeout), device_id)

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

    def _reply(self, what: str, timeout: float | None = None) -> str:
        while True:
            line = self.channel.read_line(timeout, expecting=what)
            m = _IDLE.match(line)
            if m and int(m.group(1)) == self.device_id:
                continue  # power-up or stop acknowledgement
            m = _ERROR.match(line)
            if m:
                if int(m.group(1)) != self.device_id:
                    continue  # another device on the bus
                self._raise_code(int(m.group(2)))
            return line

    def measure(self, timeout: float | None = None) -> float:
        """One distance (``sNg``), metres.

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
            No reply within the timeout.
        DeviceProtocolError
            A reply that is not ``gNg+xxxxxxxx``.
        """
        self.channel.write(f"s{self.device_id}g\r\n")
        while True:
            line = self._reply("distance reply", timeout)
            m = _DISTANCE.match(line)
            if m is None:
                raise DeviceProtocolError(
                    f"{self.channel.name}: unexpected reply {line!r} to s{self.device_id}g "
                    "(expected gNg+xxxxxxxx); check baud rate, 7E1 and the device id"
                )
            if int(m.group(1)) == self.device_id:
                return int(m.group(2)) * 1e-4

    def stop(self) -> None:
        """``sNc``: stop the current measurement (reply ``gN?``), clearing stale input first."""
        self.channel.discard_input()
        self.channel.write(f"s{self.device_id}c\r\n")
        line = self.channel.read_line(expecting="stop acknowledgement")
        if not _IDLE.match(line):
            raise DeviceProtocolError(f"{self.channel.name}: unexpected reply {line!r} to stop")

    def laser(self, on: bool) -> None:
        """``sNo`` / ``sNp``: laser pointer on or off (acknowledged ``gN?``)."""
        self.channel.write(f"s{self.device_id}{'o' if on else 'p'}\r\n")
        line = self._reply_ack()
        if not _IDLE.match(line):
            raise DeviceProtocolError(f"{self.channel.name}: unexpected reply {line!r} to laser")

    def _reply_ack(self) -> str:
        line = self.channel.read_line(expecting="acknowledgement")
        m = _ERROR.match(line)
        if m:
            self._raise_code(int(m.group(2)))
        return line
