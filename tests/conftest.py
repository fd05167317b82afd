"""Suite-wide settings. Under CI (``CI=true``) hypothesis is derandomized and has no deadline,
so a run is repeatable and a loaded machine cannot fail a property test by being slow."""

from __future__ import annotations

import os

from hypothesis import settings

settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
if os.environ.get("CI", "").lower() in ("1", "true", "yes"):
    settings.load_profile("ci")
