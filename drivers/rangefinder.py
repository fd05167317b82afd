"""What every range finder driver shares: the error classes and the opening of a driver by name.

Error codes of the devices map to these classes, so a session can tell a miss (no return:
:class:`SignalTooWeak`) from a device that needs attention (temperature, a refused command).
"""

from __future__ import annotations

from typing import Protocol

from asbuilt.errors import DeviceError

__all__ = [
    "RangeFinderError",
    "SignalTooWeak",
    "SignalTooStrong",
    "TooMuchBackgroundLight",
    "TemperatureError",
    "RangeFinderCommandError",
    "RangeFinder",
    "RANGE_FINDER_PROTOCOLS",
    "open_range_finder",
]


class RangeFinderError(DeviceError):
    """The range finder answered a measurement with an error code.

    Attributes
    ----------
    code : str
        The device's code as sent (e.g. ``"E255"`` or ``"E15"``).
    """

    def __init__(self, message: str, code: str = ""):
        super().__init__(message)
        self.code = code


class SignalTooWeak(RangeFinderError):
    """No usable return: nothing in the beam within range, a dark or grazing surface."""


class SignalTooStrong(RangeFinderError):
    """The return saturates the receiver (retro-reflector, specular surface head-on)."""


class TooMuchBackgroundLight(RangeFinderError):
    """Sunlight or another light source swamps the laser return."""


class TemperatureError(RangeFinderError):
    """The device is too hot or too cold to measure."""


class RangeFinderCommandError(RangeFinderError):
    """The device rejected a command or its interface overflowed."""


class RangeFinder(Protocol):
    """A range finder driver: :meth:`measure` returns the raw range in metres."""

    def measure(self) -> float:
        """One distance, metres (the device's own value, before calibration)."""

    def close(self) -> None:
        """Release the port."""


#: Driver names accepted by :func:`open_range_finder` and ``asbuilt scan --lrf-protocol``.
RANGE_FINDER_PROTOCOLS = ("dimetix", "ldm", "lw20")


def open_range_finder(url: str, protocol: str = "dimetix", *, timeout: float = 3.0, **options):
    """Open the range finder at ``url`` with the driver for ``protocol``.

    Parameters
    ----------
    url : str
        Device path or pyserial URL.
    protocol : {"dimetix", "ldm", "lw20"}
        Dimetix DLS/FLS, Jenoptik LDM41/42 or LightWare LW20/SF20.
    timeout : float
        Seconds to wait for a measurement.
    **options
        Passed to the driver's ``open`` (``baudrate``, ``device_id``...).
    """
    if protocol == "dimetix":
        from .dimetix import DimetixDLS

        return DimetixDLS.open(url, timeout=timeout, **options)
    if protocol == "ldm":
        from .ldm import LDM4x

        return LDM4x.open(url, timeout=timeout, **options)
    if protocol == "lw20":
        from .lw20 import LW20

        return LW20.open(url, timeout=timeout, **options)
    raise DeviceError(
        f"{url}: unknown range finder protocol {protocol!r}; use one of "
        + ", ".join(RANGE_FINDER_PROTOCOLS)
    )
