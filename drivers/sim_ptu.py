"""A simulated FLIR / Directed Perception pan-tilt unit: the ASCII protocol as a byte state machine.

Written from the manual's description (PTU-D46 User's Manual v2.14 section 4, as summarised in
/work/shared/reference/protocols.md), independently of :mod:`asbuilt.drivers.ptu`:

* a command is letters, an optional signed integer and a delimiter (space, CR or LF),
  case-insensitive; repeated delimiters are ignored;
* echo is on at power-up (``EE``/``ED``/``E``): every received byte is sent back as it arrives;
* feedback is verbose at power-up (``FV``/``FT``): ``* Current pan position is 0`` vs ``* 0``;
* success ``*``, query ``* <value>``, refusal ``! <message>``, each followed by CR LF;
* ``PP``/``TP`` absolute (query without a number), ``PO``/``TO`` relative; with limits
  enforced (``LE``, default) a target past a limit is refused with
  ``! Maximum allowable Pan position is 3090``; with ``LD`` the axis stops at the hard limit
  and ``!P`` / ``!T`` is sent on its own when the move ends;
* ``PR``/``TR`` resolution (seconds of arc per position), ``PN``/``PX``/``TN``/``TX`` limits,
  speeds and accelerations (``PS``, ``TS``, ``PA``, ``TA``, ``PB``, ``TB``, ``PU``, ``PL``...);
* ``I`` immediate mode, ``S`` slaved mode (moves wait for ``A``), ``A`` await: the ``*`` is
  sent only when the move has ended; ``H`` halt; ``R`` reset (``!T!T!P!P*``); ``V`` version.

The simulator produces *timed* output: each chunk carries the monotonic time at which the wire
would deliver it, so ``A`` really waits for a move when the rig has a finite speed.
"""

from __future__ import annotations

import re
import time

from .simrig import SimulatedRig

__all__ = ["PTUSimulator"]

_TOKEN = re.compile(rb"^([A-Za-z]+)([-+]?\d+)?$")
_VERSION = "Pan-Tilt Controller v2.14.0 (asbuilt simulator)"


class PTUSimulator:
    """The unit's firmware over a :class:`SimulatedRig`.

    Parameters
    ----------
    rig : SimulatedRig
        Shared head state; this simulator moves it.
    banner : str, optional
        A line of text the unit sends on its own, once, right after its reply to command
        number ``banner_after`` (counted from 1; 0: at power-up), as a unit that restarts or
        prints a power-up banner mid-session does (neither ``*`` nor ``!``).
    banner_after : int
    ack_at_end : bool
        Acknowledge ``PP`` / ``TP`` (immediate mode) only when the move has ended, as some
        units do, instead of at once.
    """

    def __init__(
        self,
        rig: SimulatedRig,
        *,
        banner: str | None = None,
        banner_after: int = 0,
        ack_at_end: bool = False,
    ):
        self.rig = rig
        self.ack_at_end = bool(ack_at_end)
        self.banner = banner
        self.banner_after = int(banner_after)
        self._commands = 0
        self.echo = True
        self.verbose = True
        self.enforce = True
        self.slaved = False
        self._pending: dict[str, int] = {}
        self._token = bytearray()
        self._limit_notice: bytes = b""
        self.settings = {
            "PS": 1000,
            "TS": 1000,
            "PA": 2000,
            "TA": 2000,
            "PB": 100,
            "TB": 100,
            "PU": 2902,
            "TU": 2902,
            "PL": 0,
            "TL": 0,
        }
        if rig.speed > 0:  # the speed the rig moves at is the one the unit reports
            self.settings["PS"] = self.settings["TS"] = int(round(rig.speed))

    def startup(self) -> list[tuple[float, bytes]]:
        """Output at power-up (none, unless a ``banner`` is due after 0 commands)."""
        if self.banner is not None and self.banner_after == 0:
            return [(time.monotonic(), self.banner.encode("ascii") + b"\r\n")]
        return []

    def feed(self, data: bytes) -> list[tuple[float, bytes]]:
        """Consume bytes from the host; return ``(deliver_at, bytes)`` chunks to send back."""
        now = time.monotonic()
        out: list[tuple[float, bytes]] = []
        for byte in data:
            if self.echo:
                out.append((now, bytes([byte])))
            if byte in b" \r\n":
                if self._token:
                    token = bytes(self._token)
                    self._token.clear()
                    replies = self._execute(token, now)
                    out.extend(replies)
                    self._commands += 1
                    if self.banner is not None and self._commands == self.banner_after:
                        at = max([now] + [t for t, _ in replies])
                        out.append((at, self.banner.encode("ascii") + b"\r\n"))
            else:
                self._token.append(byte)
                if len(self._token) > 64:
                    self._token.clear()
                    out.append((now, b"! Illegal Command\r\n"))
        return out

    # -- replies ---------------------------------------------------------------------------
    @staticmethod
    def _ok(now: float, value: str = "") -> list[tuple[float, bytes]]:
        text = f"* {value}" if value != "" else "*"
        return [(now, text.encode("ascii") + b"\r\n")]

    @staticmethod
    def _err(now: float, message: str) -> list[tuple[float, bytes]]:
        return [(now, f"! {message}\r\n".encode("ascii"))]

    def _value(self, now: float, terse: str, verbose: str) -> list[tuple[float, bytes]]:
        return self._ok(now, verbose if self.verbose else terse)

    # -- commands --------------------------------------------------------------------------
    def _execute(self, token: bytes, now: float) -> list[tuple[float, bytes]]:
        m = _TOKEN.match(token)
        if m is None:
            return self._err(now, "Illegal Command")
        name = m.group(1).decode("ascii").upper()
        arg = int(m.group(2)) if m.group(2) is not None else None
        rig = self.rig
        pan_min, pan_max, tilt_min, tilt_max = rig.limits
        if name in ("FT", "FV") and arg is None:
            self.verbose = name == "FV"
            return self._ok(now)
        if name in ("EE", "ED") and arg is None:
            self.echo = name == "EE"
            return self._ok(now)
        if name == "E" and arg is None:
            on = "EE" if self.echo else "ED"
            return self._value(now, on, f"Echoing {'ON' if self.echo else 'OFF'}")
        if name in ("LE", "LD") and arg is None:
            self.enforce = name == "LE"
            return self._ok(now)
        if name == "L" and arg is None:
            return self._value(
                now,
                "LE" if self.enforce else "LD",
                f"Limit bounds are {'ENABLED' if self.enforce else 'DISABLED'}",
            )
        if name in ("I", "S") and arg is None:
            self.slaved = name == "S"
            return self._ok(now)
        if name == "V" and arg is None:
            return self._ok(now, _VERSION)
        if name in ("PR", "TR") and arg is None:
            res = rig.resolution[0 if name == "PR" else 1]
            axis = "Pan" if name == "PR" else "Tilt"
            return self._value(now, f"{res:.4f}", f"{res:.4f} seconds arc per {axis} position")
        if name in ("PN", "PX", "TN", "TX") and arg is None:
            value = {"PN": pan_min, "PX": pan_max, "TN": tilt_min, "TX": tilt_max}[name]
            axis = "Pan" if name[0] == "P" else "Tilt"
            word = "Minimum" if name[1] == "N" else "Maximum"
            return self._value(now, str(value), f"{word} {axis} position is {value}")
        if name in ("PP", "TP", "PO", "TO"):
            return self._position(name, arg, now)
        if name == "A" and arg is None:
            return self._await(now)
        if name == "H" and arg is None:
            pc, tc = rig.counts(now)
            rig.move(round(pc), round(tc))
            self._pending.clear()
            return self._ok(now)
        if name == "R" and arg is None:
            end = rig.move(0, 0)
            return [(end, b"!T!T!P!P*\r\n")]
        if name in self.settings:
            if arg is None:
                axis = "Pan" if name[0] == "P" else "Tilt"
                return self._value(
                    now, str(self.settings[name]), f"{axis} {name} is {self.settings[name]}"
                )
            if arg < 0:
                return self._err(now, f"Illegal {name} argument {arg}")
            self.settings[name] = arg
            return self._ok(now)
        return self._err(now, "Illegal Command")

    def _position(self, name: str, arg: int | None, now: float) -> list[tuple[float, bytes]]:
        rig = self.rig
        pan_axis = name[0] == "P"
        axis = "Pan" if pan_axis else "Tilt"
        lo, hi = (rig.limits[0], rig.limits[1]) if pan_axis else (rig.limits[2], rig.limits[3])
        current = rig.counts(now)[0 if pan_axis else 1]
        if arg is None:
            if name[1] == "O":
                return self._err(now, "Illegal Command")
            value = int(round(current))
            return self._value(now, str(value), f"Current {axis} position is {value}")
        key = "pan" if pan_axis else "tilt"
        base = self._pending.get(key, rig.pan.target if pan_axis else rig.tilt.target)
        target = arg if name[1] == "P" else int(round(base)) + arg
        if self.enforce and target > hi:
            return self._err(now, f"Maximum allowable {axis} position is {hi}")
        if self.enforce and target < lo:
            return self._err(now, f"Minimum allowable {axis} position is {lo}")
        if target > hi or target < lo:
            target = min(max(target, lo), hi)
            self._limit_notice += b"!P" if pan_axis else b"!T"
        self._pending[key] = target
        if self.slaved:
            return self._ok(now)
        started = self._start_moves(now)
        if self.ack_at_end:
            return started + [(max(now, self.rig.move_end()), b"*\r\n")]
        return self._ok(now) + started

    def _start_moves(self, now: float) -> list[tuple[float, bytes]]:
        """Start the pending moves; a limit notice goes out when the move ends."""
        if self._pending:
            self.rig.move(self._pending.get("pan"), self._pending.get("tilt"))
            self._pending.clear()
        if not self._limit_notice:
            return []
        notice, self._limit_notice = self._limit_notice, b""
        return [(max(now, self.rig.move_end()), notice + b"\r\n")]

    def _await(self, now: float) -> list[tuple[float, bytes]]:
        out = self._start_moves(now)
        out.append((max(now, self.rig.move_end()), b"*\r\n"))
        return out
