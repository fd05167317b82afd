"""Fake devices on real pseudo-terminals, written from the device descriptions in
/work/shared/reference/protocols.md (not from the drivers), for the resynchronisation tests.

A :class:`PtyFake` serves the master end of an ``os.openpty()`` pair from a thread; the driver
opens the slave path like a serial device. Each command (bytes up to a delimiter) is handed to a
``respond(fake, command)`` callback, which schedules replies with :meth:`PtyFake.reply` after a
delay, as a device that takes time to measure or to move does. What the manuals allow and the
tests use: late replies, notices sent on their own, echoed bytes, power-up lines.
"""

from __future__ import annotations

import itertools
import os
import select
import threading
import time
import tty


class PtyFake:
    """A scripted device on a pseudo-terminal.

    Parameters
    ----------
    respond : callable ``(fake, command: str) -> None``
        Called in the serving thread for every command received.
    delimiters : bytes
        Bytes that end a command.
    echo : bool
        Send every received byte straight back (a device or bus adapter echo).
    transform : callable ``bytes -> bytes``, optional
        Applied to everything sent (e.g. 7E1 framing seen by an 8N1 host).
    empty_commands : bool
        Pass a delimiter with nothing before it on as the command ``""`` (a device that ends a
        command at CR and again at LF sees an empty one between).
    """

    def __init__(
        self, respond, *, delimiters=b"\r\n", echo=False, transform=None, empty_commands=False
    ):
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        self.path = os.ttyname(self.slave)
        self.respond = respond
        self.delimiters = delimiters
        self.echo = echo
        self.transform = transform or (lambda data: data)
        self.empty_commands = empty_commands
        self.commands: list[str] = []
        self.token = bytearray()
        self._due: list[tuple[float, int, object, bytes]] = []
        self._seq = itertools.count()
        self._lock = threading.Lock()
        self._wake_r, self._wake_w = os.pipe()
        self._stop = False
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def reply(self, data: bytes, delay: float = 0.0, tag=None) -> None:
        """Send ``data`` ``delay`` seconds from now (in due order)."""
        with self._lock:
            self._due.append((time.monotonic() + delay, next(self._seq), tag, data))
            self._due.sort(key=lambda item: item[:2])
        os.write(self._wake_w, b"x")

    def cancel(self, tag) -> None:
        """Drop the replies scheduled with ``tag`` that have not gone out yet."""
        with self._lock:
            self._due = [item for item in self._due if item[2] != tag]

    def pending(self, tag) -> bool:
        """Whether a reply with ``tag`` is still scheduled."""
        with self._lock:
            return any(item[2] == tag for item in self._due)

    def _serve(self) -> None:
        while not self._stop:
            with self._lock:
                due = self._due[0][0] if self._due else None
            timeout = None if due is None else max(0.0, due - time.monotonic())
            readable, _, _ = select.select([self.master, self._wake_r], [], [], timeout)
            if self._wake_r in readable:
                os.read(self._wake_r, 4096)
            if self.master in readable:
                try:
                    data = os.read(self.master, 4096)
                except OSError:
                    return
                for byte in data:
                    if self.echo:
                        os.write(self.master, self.transform(bytes([byte])))
                    if byte in self.delimiters:
                        if self.token or self.empty_commands:
                            command = self.token.decode("ascii", "replace")
                            self.token.clear()
                            self.commands.append(command)
                            self.respond(self, command)
                    else:
                        self.token.append(byte)
            now = time.monotonic()
            out = b""
            with self._lock:
                while self._due and self._due[0][0] <= now:
                    out += self._due.pop(0)[3]
            if out:
                os.write(self.master, self.transform(out))

    def close(self) -> None:
        """Stop serving and close the descriptors."""
        self._stop = True
        os.write(self._wake_w, b"x")
        self._thread.join(timeout=5)
        for fd in (self.master, self.slave, self._wake_r, self._wake_w):
            try:
                os.close(fd)
            except OSError:
                pass

    def __enter__(self) -> PtyFake:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def wait_until_readable(port, timeout: float = 2.0) -> None:
    """Block until ``port`` (an open pyserial port) has input: an event, not a fixed delay."""
    deadline = time.monotonic() + timeout
    while not port.in_waiting:
        if time.monotonic() > deadline:
            raise AssertionError("nothing arrived on the port")
        time.sleep(0.005)


class Head:
    """Where a fake pan-tilt unit points: the target counts reached at ``arrive`` (monotonic)."""

    def __init__(self, settle: int = 0):
        self.pan = self.tilt = 0  # counts reached
        self.target = (0, 0)
        self.arrive = 0.0
        self.moves = 0
        self.settle = settle  # counts off the target the pan axis comes to rest at

    def position(self) -> tuple[int, int]:
        if time.monotonic() >= self.arrive:
            self.pan, self.tilt = self.target[0] + self.settle, self.target[1]
        return self.pan, self.tilt


class FakeFlirPTU:
    """A FLIR/DP ASCII unit (protocols.md): letters, an optional signed integer and a space or
    CR; replies ``*``, ``* <value>``, ``! <message>`` with CR LF; ``A`` answers ``*`` when the
    move has ended. ``durations`` gives each move's duration in seconds (then ``default``).
    ``after_star`` maps a move number (1-based) to bytes sent right after its ``A``'s ``*``;
    ``instead_of_star`` to bytes sent instead of it (a notice "on its own"); ``settle`` the
    counts off its target the pan axis comes to rest at (the manual promises no exact match).
    """

    LIMITS = {"PN": -3090, "PX": 3090, "TN": -907, "TX": 604, "PR": 185.1428, "TR": 185.1428}

    def __init__(self, durations=(), default=0.0, after_star=None, instead_of_star=None, settle=0):
        self.head = Head(settle)
        self.durations = list(durations)
        self.default = default
        self.after_star = after_star or {}
        self.instead_of_star = instead_of_star or {}
        self.fake = PtyFake(self.respond, delimiters=b" \r")

    def respond(self, fake: PtyFake, command: str) -> None:
        head = self.head
        name = command.rstrip("+-0123456789").upper()
        arg = command[len(name) :]
        if name in self.LIMITS and not arg:
            return fake.reply(f"* {self.LIMITS[name]}\r\n".encode())
        if name in ("FT", "ED", "I") and not arg:
            return fake.reply(b"*\r\n")
        if name in ("PP", "TP") and not arg:
            return fake.reply(f"* {head.position()[name == 'TP']}\r\n".encode())
        if name in ("PP", "TP") and arg:
            pan, tilt = head.position()
            target = (int(arg), head.target[1]) if name == "PP" else (head.target[0], int(arg))
            if target != head.target:
                head.pan, head.tilt = pan, tilt
                head.target = target
                head.moves += 1
                duration = self.durations.pop(0) if self.durations else self.default
                head.arrive = time.monotonic() + duration
            return fake.reply(b"*\r\n")
        if name == "A" and not arg:
            delay = max(0.0, head.arrive - time.monotonic())
            move = head.moves
            if move in self.instead_of_star:
                return fake.reply(self.instead_of_star.pop(move), delay)
            return fake.reply(b"*\r\n" + self.after_star.pop(move, b""), delay)
        return fake.reply(b"! Illegal Command\r\n")
