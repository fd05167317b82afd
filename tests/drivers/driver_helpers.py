"""Helpers shared by the driver tests (a module with a unique name, importable from the tests)."""

from __future__ import annotations

import time

import asbuilt.drivers  # noqa: F401  (registers the sim URL handlers)
import numpy as np
from asbuilt.drivers.simrig import ShapesWorld, SimNoise, SimulatedRig

from asbuilt.sim.raycast import PlaneShape


class ScriptedPort:
    """A fake serial port: each complete command written gets the next scripted reply.

    ``script`` is a list of ``(expected_command, reply_bytes)``; the expected command (str,
    compared after stripping delimiters) may be None to accept anything. Replies may be split
    into several chunks (a list of bytes) to exercise partial reads. Once the script is
    exhausted the port stays silent.
    """

    def __init__(self, script, *, delimiters=b" \r\n", unsolicited=b""):
        self.script = list(script)
        self.delimiters = delimiters
        self.written: list[str] = []
        self._pending = bytearray()
        self._rx = bytearray(unsolicited)
        self.timeout = 0.01
        self.closed = False

    # the subset of the pyserial API LineChannel uses
    def write(self, data: bytes) -> int:
        for byte in data:
            if byte in self.delimiters:
                if self._pending:
                    cmd = self._pending.decode()
                    self._pending.clear()
                    self.written.append(cmd)
                    if self.script:
                        expected, reply = self.script.pop(0)
                        assert expected is None or expected == cmd, (expected, cmd)
                        chunks = reply if isinstance(reply, list) else [reply]
                        for chunk in chunks:
                            self._rx.extend(chunk)
            else:
                self._pending.append(byte)
        return len(data)

    def flush(self) -> None:
        pass

    @property
    def in_waiting(self) -> int:
        return len(self._rx)

    def read(self, size: int = 1) -> bytes:
        if not self._rx:
            time.sleep(self.timeout)
            return b""
        # deliver at most 3 bytes at a time: replies arrive in pieces
        n = min(size, len(self._rx), 3)
        out = bytes(self._rx[:n])
        del self._rx[:n]
        return out

    def reset_input_buffer(self) -> None:
        self._rx.clear()

    def close(self) -> None:
        self.closed = True


def wall_rig(distance: float = 5.0, **noise) -> SimulatedRig:
    """A rig at the origin facing a wall ``x = distance``, no noise unless asked."""
    world = ShapesWorld(
        [PlaneShape(point=np.array([distance, 0.0, 0.0]), normal=np.array([1.0, 0.0, 0.0]))]
    )
    return SimulatedRig(world, noise=SimNoise(**noise))


SCENE = {
    "format": "asbuilt-scene",
    "version": 1,
    "units": "m",
    "seed": 1,
    "stations": [
        {"id": "S1", "position": [0.0, 0.0, 1.5], "range_sigma": 0.0005, "angular_sigma_deg": 0.0}
    ],
    "objects": [
        {
            "id": "P1",
            "kind": "cylinder",
            "geometry": {
                "type": "cylinder",
                "start": [-1.0, 4.0, 1.2],
                "end": [1.0, 4.0, 1.2],
                "od": 0.3239,
            },
        },
        {
            "id": "C1",
            "kind": "cuboid",
            "geometry": {
                "type": "member",
                "start": [2.0, 5.0, 0.0],
                "end": [2.0, 5.0, 3.0],
                "section": [0.4, 0.4],
            },
        },
        {
            "id": "wall",
            "scan": False,
            "geometry": {
                "type": "plate",
                "center": [0.0, 8.0, 2.0],
                "normal": [0, -1, 0],
                "size": [14.0, 5.0],
                "thickness": 0.2,
            },
        },
        {"id": "floor", "scan": False, "geometry": {"type": "ground"}},
    ],
}
