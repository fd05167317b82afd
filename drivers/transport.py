"""Serial transport shared by every driver: open a port by URL, read lines against a deadline.

Every driver opens its port with :func:`serial.serial_for_url`, so a device path
(``/dev/ttyUSB0``), a traffic log (``spy:///dev/ttyUSB0``), a network bridge (``socket://``,
``rfc2217://``) or one of the simulator URLs (``sim-ptu://``, ``sim-lrf://``, see
:mod:`asbuilt.drivers.simport`) all work. pyserial finds a URL handler by importing
``<package>.protocol_<scheme>`` from each package in ``serial.protocol_handler_packages``;
:func:`register_url_handlers` adds ``asbuilt.drivers`` to that list.

Reads never block past an explicit deadline: a lost or silent device raises
:class:`~asbuilt.errors.DeviceTimeout` naming the port, what was expected and what to check.
"""

from __future__ import annotations

import math
import os
import stat
import sys
import time

import serial

from asbuilt.errors import DeviceError, DeviceProtocolError, DeviceTimeout

__all__ = ["register_url_handlers", "open_port", "is_pseudo_terminal", "LineChannel", "SIM_SCHEMES"]

#: URL schemes this package serves (pyserial lower-cases the scheme before the lookup).
SIM_SCHEMES = ("sim-ptu", "sim-lrf")

_PACKAGE = "asbuilt.drivers"

try:  # POSIX: tty attribute errors are not OSError subclasses
    from termios import error as _TermiosError
except ImportError:  # pragma: no cover - Windows

    class _TermiosError(Exception):
        pass


def register_url_handlers() -> None:
    """Let :func:`serial.serial_for_url` find the ``sim-ptu://`` and ``sim-lrf://`` handlers.

    Idempotent; called by :func:`open_port` and on importing :mod:`asbuilt.drivers`.
    """
    if _PACKAGE not in serial.protocol_handler_packages:
        serial.protocol_handler_packages.append(_PACKAGE)


def open_port(
    url: str,
    *,
    baudrate: int = 9600,
    bytesize: int = 8,
    parity: str = "N",
    stopbits: float = 1,
    timeout: float = 0.05,
    write_timeout: float = 1.0,
) -> serial.SerialBase:
    """Open ``url`` with :func:`serial.serial_for_url` and explicit timeouts.

    Parameters
    ----------
    url : str
        A device path or any pyserial URL (``spy://``, ``socket://``, ``sim-ptu://``...).
    baudrate, bytesize, parity, stopbits
        Line settings (ignored by the simulator URLs).
    timeout : float
        Seconds one low-level read may block: the polling interval of :class:`LineChannel`,
        which enforces the real reply deadline itself (the port's timeout is never changed
        after opening: on some ttys that reconfiguration fails).
    write_timeout : float
        Seconds a write may block.

    Returns
    -------
    serial.SerialBase
        The open port.

    Raises
    ------
    DeviceError
        The port cannot be opened (missing device, busy, unknown URL scheme), or a simulator
        URL has an option it does not know.
    """
    register_url_handlers()
    if url.partition("://")[0].lower() in SIM_SCHEMES:
        from .simport import parse_sim_url

        try:  # a misspelt option is a typo to name, not a port that cannot open
            parse_sim_url(url)
        except serial.SerialException as exc:
            raise DeviceError(f"{url}: {exc}") from None
    pty = is_pseudo_terminal(_wrapped_path(url))
    if pty:  # a pty passes bytes unchanged and cannot do 7 bits or parity (Linux refuses them)
        bytesize, parity = 8, "N"
    try:
        return serial.serial_for_url(
            url,
            baudrate=baudrate,
            bytesize=bytesize,
            parity=parity,
            stopbits=stopbits,
            timeout=timeout,
            write_timeout=write_timeout,
        )
    except (serial.SerialException, ValueError, OSError, _TermiosError) as exc:
        if pty or url.startswith("/dev/pts/"):  # a pty, or one whose server has closed it
            raise DeviceError(
                f"{url}: cannot open the pseudo-terminal ({exc}); check that the simulator "
                "(asbuilt simulate-device) or the program serving it is still running"
            ) from None
        raise DeviceError(
            f"{url}: cannot open the port ({exc}); check the cable, the device path and "
            "that no other program holds it"
        ) from None


#: Linux's device numbers (major) of Unix98 pseudo-terminal slaves (/dev/pts/N): 136-143
#: (Documentation/admin-guide/devices.txt, "Unix98 PTY slaves").
_PTY_SLAVE_MAJORS = range(136, 144)


def _wrapped_path(url: str) -> str:
    """The device path under pyserial's ``spy://`` wrapper (``spy://PATH?options``, which logs
    the traffic of the port at PATH), else ``url`` itself."""
    if url.startswith("spy://"):
        return url[len("spy://") :].split("?", 1)[0]
    return url


def is_pseudo_terminal(url: str) -> bool:
    """Whether ``url`` is a plain path to a Linux pseudo-terminal slave (``/dev/pts/N``).

    Such a tty (the device simulators', ``socat``'s) passes bytes unchanged and keeps 8 data
    bits without parity whatever is asked; :func:`open_port` opens it 8N1, as a 7E1 request
    it can change nothing of fails with EINVAL on recent kernels.
    """
    if "://" in url or not sys.platform.startswith("linux"):
        return False
    try:
        info = os.stat(url)
    except (OSError, ValueError):
        return False
    return stat.S_ISCHR(info.st_mode) and os.major(info.st_rdev) in _PTY_SLAVE_MAJORS


def _seconds(value, what: str, zero: bool = False) -> float:
    """``value`` as seconds: finite and > 0 (>= 0 with ``zero``), else ValueError."""
    seconds = float(value)
    if not math.isfinite(seconds) or seconds < 0 or (seconds == 0 and not zero):
        raise ValueError(f"{what} must be a finite number of seconds > 0, got {value!r}")
    return seconds


#: Byte translation clearing bit 7 (the parity bit a 7E1 device's byte carries on an 8N1 port).
_SEVEN_BITS = bytes(b & 0x7F for b in range(256))


def write_bytes(port, name: str, data: bytes, device: str = "device") -> None:
    """Send ``data`` on ``port`` at once; DeviceTimeout or DeviceError, naming ``name``, if the
    port fails (``device``: what to check the power of)."""
    try:
        port.write(data)
        port.flush()
    except serial.SerialTimeoutException:
        raise DeviceTimeout(
            f"{name}: write timed out; check the cable and the {device}'s power"
        ) from None
    except (serial.SerialException, OSError, _TermiosError) as exc:
        raise DeviceError(f"{name}: write failed ({exc}); the cable may be unplugged") from None


def read_bytes(port, name: str, least: int = 1) -> bytes:
    """What ``port`` has received: at least ``least`` bytes, or what arrives within the port's
    timeout (``least=0``: only what has arrived, no wait); DeviceError, naming ``name``, if the
    port fails."""
    try:
        return port.read(max(least, port.in_waiting))
    except (serial.SerialException, OSError, _TermiosError) as exc:
        raise DeviceError(f"{name}: read failed ({exc}); the cable may be unplugged") from None


def reset_input(port, name: str) -> None:
    """Drop the port's pending input; DeviceError, naming ``name``, if the port fails."""
    try:
        port.reset_input_buffer()
    except (serial.SerialException, OSError, _TermiosError) as exc:
        raise DeviceError(f"{name}: cannot reset the input ({exc})") from None


class LineChannel:
    """Line-oriented ASCII exchange over an open port, with deadlines.

    Replies of the devices here end with CR LF; a bare CR or LF also ends a line, so partial
    writes, missing LFs and stray blank lines do not desynchronise the reader.

    Parameters
    ----------
    port : serial.SerialBase
        An open port (from :func:`open_port`).
    name : str
        Device name for messages (e.g. ``"pan-tilt unit on /dev/ttyUSB0"``).
    timeout : float
        Default seconds to wait for one reply line.
    seven_bit : bool
        The device sends 7 data bits (Dimetix 7E1): bit 7 of every byte received is cleared.
        A port that cannot do 7 bits or parity (a pseudo-terminal, :func:`open_port` opens it
        8N1) passes the parity bit through as bit 7; a real 7-bit port never sets it.
    """

    def __init__(
        self, port: serial.SerialBase, name: str, timeout: float = 1.0, seven_bit: bool = False
    ):
        self.port = port
        self.name = name
        self.timeout = _seconds(timeout, "timeout")
        self.seven_bit = bool(seven_bit)
        self._buffer = bytearray()

    def _received(self, chunk: bytes) -> None:
        """Append ``chunk`` to the line buffer (bit 7 cleared for a 7-bit device)."""
        self._buffer.extend(chunk.translate(_SEVEN_BITS) if self.seven_bit else chunk)
        if len(self._buffer) > 4096:
            raise DeviceProtocolError(f"{self.name}: 4 KiB without a line end; check the baud rate")

    def write(self, text: str) -> None:
        """Send ``text`` (ASCII) at once; DeviceError if the port fails (cable unplugged)."""
        write_bytes(self.port, self.name, text.encode("ascii"))

    def discard_input(self) -> None:
        """Forget buffered and pending input (stale replies, power-up banners)."""
        self._buffer.clear()
        reset_input(self.port, self.name)

    def pending_lines(self) -> list[str]:
        """The complete lines already received, without waiting (a partial line stays buffered).

        Raises
        ------
        DeviceError, DeviceProtocolError
            The port fails, or a line holds non-ASCII bytes.
        """
        try:
            while self.port.in_waiting:
                chunk = self.port.read(self.port.in_waiting)
                if not chunk:
                    break
                self._received(chunk)
        except (serial.SerialException, OSError, _TermiosError) as exc:
            raise DeviceError(
                f"{self.name}: read failed ({exc}); the cable may be unplugged"
            ) from None
        lines = []
        while (line := self._pop_line()) is not None:
            lines.append(line)
        return lines

    def _pop_line(self) -> str | None:
        while True:
            for i, byte in enumerate(self._buffer):
                if byte in (10, 13):
                    raw = bytes(self._buffer[:i])
                    del self._buffer[: i + 1]
                    break
            else:
                return None
            if raw.strip():
                try:
                    return raw.decode("ascii").strip()
                except UnicodeDecodeError:
                    raise DeviceProtocolError(
                        f"{self.name}: received non-ASCII bytes {raw!r}; check the baud rate "
                        "and line settings"
                    ) from None

    def read_line(self, timeout: float | None = None, expecting: str = "reply") -> str:
        """Return the next non-empty line without its terminator.

        Parameters
        ----------
        timeout : float, optional
            Seconds to wait (default: the channel's timeout).
        expecting : str
            What was awaited, for the timeout message.

        Raises
        ------
        DeviceTimeout
            No complete line arrived before the deadline.
        DeviceProtocolError
            The line holds non-ASCII bytes (wrong baud rate, noise).
        ValueError
            ``timeout`` is not a finite number >= 0 (a NaN deadline would never expire).
        """
        wait = self.timeout if timeout is None else _seconds(timeout, "timeout", zero=True)
        deadline = time.monotonic() + wait
        while True:
            line = self._pop_line()
            if line is not None:
                return line
            remaining = deadline - time.monotonic()
            if not remaining > 0:  # also true for NaN: never wait without a deadline
                partial = f" (partial {bytes(self._buffer)!r})" if self._buffer else ""
                raise DeviceTimeout(
                    f"{self.name}: no {expecting} within {wait:g} s{partial}; check the cable, "
                    "the port, the baud rate and that the device is powered"
                )
            chunk = read_bytes(self.port, self.name)
            if chunk:
                self._received(chunk)

    def close(self) -> None:
        """Close the port (idempotent)."""
        try:
            self.port.close()
        except (serial.SerialException, OSError):
            pass
