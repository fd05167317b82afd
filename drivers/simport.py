"""pyserial URL handlers for the device simulators: ``sim-ptu://RIG?...`` and ``sim-lrf://RIG?...``.

``serial.serial_for_url("sim-ptu://lab?scene=scene.json")`` returns a port whose other end is a
:class:`~asbuilt.drivers.sim_ptu.PTUSimulator`; ``sim-lrf://lab?protocol=dimetix`` one whose other
end is a range finder simulator. Both URLs with the same host part (``lab``) share one
:class:`~asbuilt.drivers.simrig.SimulatedRig`, so the range finder measures where the head points.

URL query options
-----------------
Rig (either URL; the first one opened for a rig must give ``scene``):
    ``scene`` (scene .json or mesh path), ``calibration`` (true calibration file),
    ``range_sigma`` (m), ``angle_sigma`` (rad), ``dropout`` (0-1), ``divergence`` (rad),
    ``min_cos``, ``max_range`` (m), ``seed``, ``speed`` (positions/s, 0 = instant),
    ``station`` (scene station id; default the first).
Port:
    ``protocol`` (sim-ptu: ``flir`` (default) or ``pelco-d``; sim-lrf: ``dimetix`` (default),
    ``ldm`` or ``lw20``), ``device_id`` (Dimetix id), ``address`` (Pelco-D address, 1),
    ``trickle`` (Pelco-D: seconds between reply bytes), ``prefix`` (LW20: label before a distance),
    ``silent=1`` (the device never answers: timeouts), ``unplug_after=N`` (after N writes every
    read and write fails as if the cable were pulled).

pyserial imports ``asbuilt.drivers.protocol_sim-ptu`` for the scheme ``sim-ptu`` (the scheme,
lower-cased, is appended to ``protocol_``); those two small modules re-export :class:`Serial`.
"""

from __future__ import annotations

import threading
import time
import urllib.parse

from serial.serialutil import PortNotOpenError, SerialBase, SerialException

from asbuilt.errors import AsbuiltError

__all__ = ["Serial", "make_device", "parse_sim_url", "url_options"]


#: URL options of one port (either scheme), and of each scheme's device (docs/drivers.md).
PORT_OPTIONS = ("silent", "unplug_after")
DEVICE_OPTIONS = {
    "sim-ptu": ("protocol", "address", "trickle"),
    "sim-lrf": ("protocol", "device_id", "prefix"),
}


def url_options(scheme: str) -> tuple[str, ...]:
    """Every query key a ``scheme`` URL accepts (rig, device and port options), sorted."""
    from .simrig import RIG_OPTIONS

    return tuple(sorted({*RIG_OPTIONS, *DEVICE_OPTIONS[scheme], *PORT_OPTIONS}))


def parse_sim_url(url: str) -> tuple[str, str, dict[str, str]]:
    """Split ``sim-ptu://rig?k=v`` into ``(scheme, rig, options)``.

    Raises
    ------
    SerialException
        Another scheme, or a query key the scheme does not know (a misspelt ``calibraton=``
        would otherwise give an ideal rig), naming the key and the valid ones.
    """
    parts = urllib.parse.urlsplit(url)
    scheme = parts.scheme.lower()
    if scheme not in ("sim-ptu", "sim-lrf"):
        raise SerialException(f"{url}: expected sim-ptu://RIG?... or sim-lrf://RIG?...")
    name = parts.netloc or parts.path.strip("/") or "default"
    options = {k: v[-1] for k, v in urllib.parse.parse_qs(parts.query, True).items()}
    valid = url_options(scheme)
    for key in options:
        if key not in valid:
            raise SerialException(f"unknown URL option {key!r}; use {', '.join(valid)}")
    return scheme, name, options


def make_device(scheme: str, rig, options: dict[str, str], settings: dict | None = None):
    """The simulator for ``scheme`` over ``rig`` (port options: protocol, device_id, address,
    trickle, prefix; ``settings``: the FLIR, Pelco-D, Dimetix or LDM simulator class's keyword options,
    e.g. ``measure_time``)."""
    settings = dict(settings or {})
    if scheme == "sim-ptu":
        protocol = options.get("protocol", "flir").lower()
        if protocol == "pelco-d":
            from .sim_pelco import PelcoDSimulator

            address = int(options.get("address", 1))
            if not 1 <= address <= 255:
                raise ValueError(f"address must be a Pelco-D address 1-255, not {address}")
            settings.setdefault("trickle", float(options.get("trickle", 0)))
            return PelcoDSimulator(rig, address, **settings)
        if protocol != "flir":
            raise SerialException(
                f"unknown simulated pan-tilt protocol {protocol!r}; use flir or pelco-d"
            )
        from .sim_ptu import PTUSimulator

        return PTUSimulator(rig, **settings)
    from .sim_lrf import DimetixSimulator, LDMSimulator

    protocol = options.get("protocol", "dimetix").lower()
    if protocol == "dimetix":
        return DimetixSimulator(rig, int(options.get("device_id", 0)), **settings)
    if protocol == "ldm":
        return LDMSimulator(rig, **settings)
    if protocol == "lw20":
        from .sim_lw20 import LW20Simulator

        return LW20Simulator(rig, options.get("prefix", ""), **settings)
    raise SerialException(
        f"unknown simulated range finder protocol {protocol!r}; use dimetix, ldm or lw20"
    )


class Serial(SerialBase):
    """A port whose far end is a device simulator (see the module docstring for the URL)."""

    def __init__(self, *args, **kwargs):
        self._device = None
        self._outbox: list[tuple[float, bytes]] = []
        self._cond = threading.Condition()
        self._writes = 0
        self._silent = False
        self._unplug_after: int | None = None
        super().__init__(*args, **kwargs)

    def open(self) -> None:
        if self.is_open:
            raise SerialException("Port is already open.")
        if self._port is None:
            raise SerialException("Port must be configured before it can be used.")
        from .simrig import get_rig

        scheme, name, options = parse_sim_url(self.port)
        try:
            rig = get_rig(name, options)
            self._device = make_device(scheme, rig, options)
            self._silent = options.get("silent", "0") not in ("0", "", "false")
            self._unplug_after = int(options["unplug_after"]) if "unplug_after" in options else None
        except (AsbuiltError, ValueError) as exc:
            raise SerialException(str(exc)) from None
        self._outbox = [] if self._silent else list(self._device.startup())
        self._writes = 0
        self.is_open = True

    def close(self) -> None:
        with self._cond:
            self.is_open = False
            self._cond.notify_all()
        super().close()

    def _reconfigure_port(self, *args, **kwargs) -> None:
        """Line settings mean nothing to a simulator."""

    def _update_dtr_state(self) -> None:
        pass

    def _update_rts_state(self) -> None:
        pass

    def _update_break_state(self) -> None:
        pass

    def _check(self) -> None:
        if not self.is_open:
            raise PortNotOpenError()
        if self._unplug_after is not None and self._writes > self._unplug_after:
            raise SerialException("device disconnected (simulated unplugged cable)")

    def _ready(self, now: float) -> int:
        return sum(len(chunk) for at, chunk in self._outbox if at <= now)

    @property
    def in_waiting(self) -> int:
        with self._cond:
            self._check()
            return self._ready(time.monotonic())

    def read(self, size: int = 1) -> bytes:
        deadline = None if self._timeout is None else time.monotonic() + self._timeout
        data = bytearray()
        with self._cond:
            while len(data) < size:
                self._check()
                now = time.monotonic()
                while self._outbox and self._outbox[0][0] <= now and len(data) < size:
                    at, chunk = self._outbox.pop(0)
                    take = size - len(data)
                    data += chunk[:take]
                    if len(chunk) > take:
                        self._outbox.insert(0, (at, chunk[take:]))
                if len(data) >= size:
                    break
                if deadline is not None and now >= deadline:
                    break
                wake = [deadline] if deadline is not None else []
                if self._outbox:
                    wake.append(self._outbox[0][0])
                self._cond.wait(None if not wake else max(0.0, min(wake) - now))
        return bytes(data)

    def write(self, data) -> int:
        data = bytes(data)
        with self._cond:
            self._check()
            self._writes += 1
            if self._unplug_after is not None and self._writes > self._unplug_after:
                raise SerialException("device disconnected (simulated unplugged cable)")
            if not self._silent:
                with self._device.rig.lock:
                    produced = self._device.feed(data)
                self._outbox.extend(produced)
                self._outbox.sort(key=lambda item: item[0])
            self._cond.notify_all()
        return len(data)

    def reset_input_buffer(self) -> None:
        with self._cond:
            self._check()
            now = time.monotonic()
            self._outbox = [(at, chunk) for at, chunk in self._outbox if at > now]

    def reset_output_buffer(self) -> None:
        self._check()

    @property
    def out_waiting(self) -> int:
        return 0

    @property
    def cts(self) -> bool:
        return True

    @property
    def dsr(self) -> bool:
        return True

    @property
    def ri(self) -> bool:
        return False

    @property
    def cd(self) -> bool:
        return True
