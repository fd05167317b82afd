"""Serve the device simulators on pseudo-terminals, so real drivers talk to them over a real tty.

:class:`PtyServer` opens two pseudo-terminal pairs (:func:`os.openpty`), puts the slave ends in
raw mode and runs the pan-tilt and range finder simulators on the master ends in a thread.
A driver opens the slave paths (``/dev/pts/N``) like any serial device; ``asbuilt
simulate-device`` prints them and serves until Ctrl-C. POSIX only.

A pseudo-terminal cannot do 7-bit characters or parity: Linux keeps its slave at CS8 without
PARENB whatever is asked, and (recent kernels) fails ``tcsetattr`` with EINVAL when *nothing*
it was asked could be changed. A 7E1 client (pyserial opening a Dimetix 7E1) that re-opens the
tty with the settings it left there asks only for CS7 and PARENB, and fails. So the server
marks the slave as "not configured" by setting ``IXANY`` (harmless: without ``IXON``, which
every serial client clears, it does nothing) when it starts and whenever the client has sent
something; the next open clears it again, so its ``tcsetattr`` changes something and succeeds.
"""

from __future__ import annotations

import os
import select
import termios
import threading
import time
import tty

from asbuilt.errors import DeviceError

from .simport import make_device

__all__ = ["PtyServer"]


def _mark_unconfigured(fd: int) -> None:
    """Set ``IXANY`` on the pty slave ``fd`` so that a client's next open changes something.

    See the module docstring: without a change it can make, Linux refuses a 7E1 client's
    ``tcsetattr`` with EINVAL on its second open of the same tty.
    """
    attrs = termios.tcgetattr(fd)
    if not attrs[0] & termios.IXANY:
        attrs[0] |= termios.IXANY
        termios.tcsetattr(fd, termios.TCSANOW, attrs)


class _Endpoint:
    def __init__(self, device):
        self.device = device
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        _mark_unconfigured(self.slave)
        self.path = os.ttyname(self.slave)
        self.outbox: list[tuple[float, bytes]] = list(device.startup())


class PtyServer:
    """Both simulators of one rig on two pseudo-terminals.

    Parameters
    ----------
    rig : SimulatedRig
    lrf_protocol : {"dimetix", "ldm", "lw20"}
    device_id : int
        Dimetix device id.
    ptu_protocol : {"flir", "pelco-d"}
        The pan-tilt head's protocol.
    ptu_address : int
        Pelco-D address (1-255).
    ptu_options, lrf_options : dict, optional
        Keyword options of the FLIR, Pelco-D, Dimetix and LDM simulators
        (:class:`~asbuilt.drivers.sim_ptu.PTUSimulator`,
        :class:`~asbuilt.drivers.sim_pelco.PelcoDSimulator`, :mod:`~asbuilt.drivers.sim_lrf`):
        a measuring time, a banner, 7E1 bytes, a signed tilt...

    Attributes
    ----------
    ptu_path, lrf_path : str
        The tty paths to give the drivers (valid after :meth:`start`).
    """

    def __init__(
        self,
        rig,
        lrf_protocol: str = "dimetix",
        device_id: int = 0,
        *,
        ptu_protocol: str = "flir",
        ptu_address: int = 1,
        ptu_options: dict | None = None,
        lrf_options: dict | None = None,
    ):
        self.rig = rig
        self.ptu_options = dict(ptu_options or {})
        self.lrf_options = dict(lrf_options or {})
        self.lrf_protocol = lrf_protocol
        self.device_id = device_id
        self.ptu_protocol = ptu_protocol
        self.ptu_address = ptu_address
        self._endpoints: list[_Endpoint] = []
        self._thread: threading.Thread | None = None
        self._wake_r = self._wake_w = -1
        self._stop = threading.Event()
        self.error: BaseException | None = None

    @property
    def ptu_path(self) -> str:
        return self._endpoints[0].path

    @property
    def lrf_path(self) -> str:
        return self._endpoints[1].path

    def start(self) -> PtyServer:
        """Open the pseudo-terminals and start serving in a daemon thread."""
        try:
            self._endpoints = [
                _Endpoint(
                    make_device(
                        "sim-ptu",
                        self.rig,
                        {"protocol": self.ptu_protocol, "address": str(self.ptu_address)},
                        self.ptu_options,
                    )
                ),
                _Endpoint(
                    make_device(
                        "sim-lrf",
                        self.rig,
                        {"protocol": self.lrf_protocol, "device_id": str(self.device_id)},
                        self.lrf_options,
                    )
                ),
            ]
        except OSError as exc:
            raise DeviceError(f"cannot open pseudo-terminals ({exc.strerror})") from None
        except Exception as exc:  # serial.SerialException for a bad protocol name
            raise DeviceError(str(exc)) from None
        self._wake_r, self._wake_w = os.pipe()
        self._thread = threading.Thread(target=self._serve, name="asbuilt-pty-sim", daemon=True)
        self._thread.start()
        return self

    def _serve(self) -> None:
        try:
            while not self._stop.is_set():
                now = time.monotonic()
                due = [at for ep in self._endpoints for at, _ in ep.outbox]
                timeout = max(0.0, min(due) - now) if due else None
                fds = [ep.master for ep in self._endpoints] + [self._wake_r]
                readable, _, _ = select.select(fds, [], [], timeout)
                if self._wake_r in readable:
                    break
                for ep in self._endpoints:
                    if ep.master in readable:
                        try:
                            data = os.read(ep.master, 4096)
                        except OSError:
                            data = b""
                        if data:
                            _mark_unconfigured(ep.slave)  # the client has configured the tty
                            with self.rig.lock:
                                ep.outbox.extend(ep.device.feed(data))
                            ep.outbox.sort(key=lambda item: item[0])
                    now = time.monotonic()
                    ready = b""
                    while ep.outbox and ep.outbox[0][0] <= now:
                        ready += ep.outbox.pop(0)[1]
                    if ready:
                        os.write(ep.master, ready)
        except BaseException as exc:  # kept for the caller; the thread must not die silently
            self.error = exc

    def stop(self) -> None:
        """Stop serving and close every file descriptor (idempotent)."""
        self._stop.set()
        if self._wake_w >= 0:
            os.write(self._wake_w, b"x")
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        for ep in self._endpoints:
            for fd in (ep.master, ep.slave):
                try:
                    os.close(fd)
                except OSError:
                    pass
        self._endpoints = []
        for fd in (self._wake_r, self._wake_w):
            if fd >= 0:
                try:
                    os.close(fd)
                except OSError:
                    pass
        self._wake_r = self._wake_w = -1

    def __enter__(self) -> PtyServer:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()
