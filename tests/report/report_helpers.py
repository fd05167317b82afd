"""Shared helpers for the report tests (fixtures are in conftest.py): models, an HTML structure checker, headless Chromium.

The browser is driven over the DevTools protocol through ``--remote-debugging-pipe`` (JSON
messages separated by NUL bytes on file descriptors 3 and 4), so no extra Python package is
needed: console errors, uncaught exceptions and failed loads are all collected.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import tempfile
import time
from html.parser import HTMLParser
from pathlib import Path

import numpy as np

from asbuilt.findings import Finding, Suggestion
from asbuilt.model import Bend, Component, Model, Spool, Straight
from asbuilt.primitives import Cuboid, Cylinder

ROOT = Path(__file__).resolve().parents[2]

# NPS 4 STD (ASME B36.10M): OD 114.3 mm, wall 6.02 mm; B16.9 90 degree LR elbow radius 152 mm.
OD4, WALL4, LR4 = 0.1143, 0.00602, 0.152


def known_model(findings=()) -> Model:
    """A spool of two 1 m NPS 4 STD pipes joined by a 90 degree LR elbow, a 0.4 x 0.4 x 3 m
    column and a 2 m diameter x 3 m tank (no fits: quantities only)."""
    r = OD4 / 2
    p1 = Straight([0, 0, 1], [1, 0, 1], r, WALL4)
    bend = Bend([1, 0, 1], [1 + LR4, LR4, 1], [1, LR4, 1], r, WALL4)
    p2 = Straight([1 + LR4, LR4, 1], [1 + LR4, 1 + LR4, 1], r, WALL4)
    common = {"spool": "SP-1", "nominal": "4", "schedule": "STD"}
    components = (
        Component("P1", "pipe", p1, sources=("P1",), **common),
        Component("P1-P2", "elbow", bend, **common),
        Component("P2", "pipe", p2, sources=("P2",), **common),
        Component(
            "C1",
            "cuboid",
            Cuboid([3, 3, 1.5], np.eye(3), [0.4, 0.4, 3.0]),
            sources=("C1",),
            label="column C1",
        ),
        Component(
            "TK1",
            "cylinder",
            Cylinder([6, 0, 1.5], [0, 0, 1], 1.0, 3.0),
            sources=("TK1",),
            label="tank",
        ),
    )
    spool = Spool("SP-1", ("P1", "P1-P2", "P2"), 2.0)
    return Model(
        components=components,
        name="known model",
        catalog="asme-b36.10m",
        spools=(spool,),
        findings=tuple(findings),
    )


def tiny_glb(path: Path) -> Path:
    """Write a minimal valid GLB (glTF 2.0 binary: 12-byte header and one JSON chunk padded with
    spaces to 4 bytes, as the glTF 2.0 specification's "GLB File Format" section lays out)."""
    import struct

    content = json.dumps({"asset": {"version": "2.0", "generator": "asbuilt tests"}}).encode()
    content += b" " * (-len(content) % 4)
    chunk = struct.pack("<II", len(content), 0x4E4F534A) + content  # "JSON"
    path.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + len(chunk)) + chunk)  # "glTF"
    return path


def many_findings(model: Model, per_object: int = 3) -> tuple[Finding, ...]:
    """Several findings of every severity on every component (for the 'many findings' cases)."""
    severities = ("error", "warning", "info")
    found = []
    for i, comp in enumerate(model.components):
        for j in range(per_object):
            severity = severities[(i + j) % 3]
            found.append(
                Finding(
                    code=f"AB9{j:02d}",
                    slug=f"test-rule-{j}",
                    severity=severity,
                    objects=(comp.id,),
                    message=f"{comp.id} <breaks> rule {j} & needs a look",
                    measured=0.01 * (j + 1),
                    allowed=0.005,
                    stderr=0.001,
                    unit="m",
                    suggestions=(Suggestion(f"rescan {comp.id}", {"object": comp.id}),),
                    unverifiable=j == 2,
                )
            )
    return tuple(found)


# ----------------------------------------------------------------------------------------------
# HTML structure


VOID = {
    "area",
    "base",
    "br",
    "col",
    "embed",
    "hr",
    "img",
    "input",
    "link",
    "meta",
    "source",
    "track",
    "wbr",
}


class StructureChecker(HTMLParser):
    """Builds a tag stack: every non-void element must be closed, in order; ids must be unique
    and every ``href="#id"`` must name an element of the page."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack: list[tuple[str, tuple]] = []
        self.errors: list[str] = []
        self.ids: list[str] = []
        self.links: list[str] = []
        self.tags: dict[str, int] = {}
        self.doctype = None

    def handle_decl(self, decl):
        self.doctype = decl

    def _attrs(self, tag, attrs):
        self.tags[tag] = self.tags.get(tag, 0) + 1
        for name, value in attrs:
            if name == "id":
                self.ids.append(value)
            if name in ("href", "xlink:href") and value and value.startswith("#"):
                self.links.append(value[1:])

    def handle_starttag(self, tag, attrs):
        self._attrs(tag, attrs)
        if tag not in VOID:
            self.stack.append((tag, self.getpos()))

    def handle_startendtag(self, tag, attrs):
        self._attrs(tag, attrs)

    def handle_endtag(self, tag):
        if tag in VOID:
            self.errors.append(f"end tag for void element </{tag}> at {self.getpos()}")
            return
        if not self.stack:
            self.errors.append(f"stray </{tag}> at {self.getpos()}")
            return
        open_tag, where = self.stack.pop()
        if open_tag != tag:
            self.errors.append(
                f"<{open_tag}> opened at {where} closed by </{tag}> at {self.getpos()}"
            )

    def finish(self) -> list[str]:
        self.close()
        errors = list(self.errors)
        errors += [f"<{tag}> opened at {where} never closed" for tag, where in self.stack]
        duplicates = {i for i in self.ids if self.ids.count(i) > 1}
        errors += [f"duplicate id {i!r}" for i in sorted(duplicates)]
        known = set(self.ids)
        errors += [f"link to missing #{t}" for t in sorted(set(self.links) - known)]
        if (self.doctype or "").lower() != "doctype html":
            errors.append(f"doctype is {self.doctype!r}, not 'DOCTYPE html'")
        return errors


def check_html(text: str) -> StructureChecker:
    """Parse ``text``; fail the test listing every structure error."""
    checker = StructureChecker()
    checker.feed(text)
    errors = checker.finish()
    assert not errors, "\n".join(errors[:20])
    return checker


# ----------------------------------------------------------------------------------------------
# headless Chromium over the DevTools pipe


def _ci() -> bool:
    return os.environ.get("CI", "").lower() in ("true", "1", "yes")


def _chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome", "chrome"):
        found = shutil.which(name)
        if found:
            return found
    return None


def _pipe_fds(read_end: int, write_end: int) -> None:
    """In the child: put the pipe ends on fds 3 and 4 (copies above 10 first, so that neither
    overwrites the other)."""
    import fcntl

    high_read = fcntl.fcntl(read_end, fcntl.F_DUPFD, 10)
    high_write = fcntl.fcntl(write_end, fcntl.F_DUPFD, 10)
    os.dup2(high_read, 3)  # os.dup2 makes the copies inheritable
    os.dup2(high_write, 4)
    os.close(high_read)
    os.close(high_write)


class Browser:
    """One headless Chromium talking DevTools over a pipe."""

    def __init__(self, executable: str):
        self.profile = tempfile.mkdtemp(prefix="asbuilt-chromium-")
        to_chrome_r, self._to_chrome = os.pipe()
        self._from_chrome, from_chrome_w = os.pipe()
        # Chromium reads commands on fd 3 and writes replies on fd 4.
        self.process = subprocess.Popen(
            [
                executable,
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--disable-extensions",
                f"--user-data-dir={self.profile}",
                "--remote-debugging-pipe",
                "about:blank",
            ],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            close_fds=False,  # only fds 3 and 4 are inheritable (PEP 446)
            preexec_fn=lambda: _pipe_fds(to_chrome_r, from_chrome_w),
        )
        os.close(to_chrome_r)
        os.close(from_chrome_w)
        self._buffer = b""
        self._next = 0
        self.events: list[dict] = []

    def _send(self, method: str, params=None, session=None) -> int:
        self._next += 1
        message = {"id": self._next, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        os.write(self._to_chrome, json.dumps(message).encode() + b"\0")
        return self._next

    def _read(self, deadline: float) -> dict:
        while b"\0" not in self._buffer:
            if time.monotonic() > deadline:
                raise TimeoutError("Chromium did not answer in time")
            chunk = os.read(self._from_chrome, 1 << 16)
            if not chunk:
                raise RuntimeError("Chromium closed the DevTools pipe")
            self._buffer += chunk
        raw, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(raw)

    def call(self, method: str, params=None, session=None, timeout: float = 30.0) -> dict:
        wanted = self._send(method, params, session)
        deadline = time.monotonic() + timeout
        while True:
            message = self._read(deadline)
            if message.get("id") == wanted:
                if "error" in message:
                    raise RuntimeError(f"{method}: {message['error']}")
                return message.get("result", {})
            self.events.append(message)

    def wait_for(self, method: str, session: str, timeout: float = 30.0) -> dict:
        for index, event in enumerate(self.events):
            if event.get("method") == method and event.get("sessionId") == session:
                return self.events.pop(index)
        deadline = time.monotonic() + timeout
        while True:
            message = self._read(deadline)
            if message.get("method") == method and message.get("sessionId") == session:
                return message
            self.events.append(message)

    def open(self, url: str, width: int = 1280, height: int = 2000) -> Page:
        target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self.call("Target.attachToTarget", {"targetId": target, "flatten": True})[
            "sessionId"
        ]
        for domain in ("Page", "Runtime", "Log", "Network"):
            self.call(f"{domain}.enable", session=session)
        self.call(
            "Emulation.setDeviceMetricsOverride",
            {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False},
            session=session,
        )
        self.call("Page.navigate", {"url": url}, session=session)
        self.wait_for("Page.loadEventFired", session)
        return Page(self, session)

    def close(self) -> None:
        try:
            self._send("Browser.close")
            self.process.wait(timeout=10)
        except Exception:
            self.process.kill()
            self.process.wait(timeout=10)
        finally:
            os.close(self._to_chrome)
            os.close(self._from_chrome)
            shutil.rmtree(self.profile, ignore_errors=True)


class Page:
    def __init__(self, browser: Browser, session: str):
        self.browser = browser
        self.session = session

    def evaluate(self, expression: str):
        result = self.browser.call(
            "Runtime.evaluate",
            {"expression": expression, "returnByValue": True},
            session=self.session,
        )
        if "exceptionDetails" in result:
            raise RuntimeError(f"{expression}: {result['exceptionDetails']}")
        return result["result"].get("value")

    def problems(self) -> list[str]:
        """Console errors and warnings, uncaught exceptions, failed loads and error log entries
        seen so far on this page."""
        self.evaluate("1")  # flush pending events
        found = []
        for event in self.browser.events:
            if event.get("sessionId") != self.session:
                continue
            method, params = event.get("method"), event.get("params", {})
            if method == "Runtime.consoleAPICalled" and params.get("type") in (
                "error",
                "warning",
                "assert",
            ):
                args = " ".join(str(a.get("value", a.get("description"))) for a in params["args"])
                found.append(f"console.{params['type']}: {args}")
            elif method == "Runtime.exceptionThrown":
                found.append(
                    f"exception: {params['exceptionDetails'].get('text')} "
                    f"{params['exceptionDetails'].get('exception', {}).get('description')}"
                )
            elif method == "Log.entryAdded" and params["entry"].get("level") in (
                "error",
                "warning",
            ):
                found.append(
                    f"log {params['entry']['level']}: {params['entry'].get('text')} "
                    f"{params['entry'].get('url', '')}"
                )
            elif method == "Network.loadingFailed":
                found.append(f"load failed: {params.get('errorText')}")
        return found

    def requests(self) -> list[str]:
        """URLs the page asked the network for."""
        return [
            e["params"]["request"]["url"]
            for e in self.browser.events
            if e.get("sessionId") == self.session and e.get("method") == "Network.requestWillBeSent"
        ]

    def screenshot(self, path, full: bool = True) -> None:
        """Save a PNG of the page (``full``: the whole page, else the viewport)."""
        import base64

        data = self.browser.call(
            "Page.captureScreenshot",
            {"format": "png", "captureBeyondViewport": full},
            session=self.session,
        )["data"]
        Path(path).write_bytes(base64.b64decode(data))
