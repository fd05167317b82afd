"""Package discovery for the fixed repository layout (everything else is in pyproject.toml).

The top-level folders drivers/ and catalogs/ install as the subpackages asbuilt.drivers and
asbuilt.catalogs (see ``package-dir`` in pyproject.toml); setuptools' automatic discovery only
finds folders named after their package, so list them here.
"""

from setuptools import find_packages, setup

packages = find_packages(".", include=["asbuilt", "asbuilt.*"])
packages += ["asbuilt.drivers"] + [f"asbuilt.drivers.{p}" for p in find_packages("drivers")]
packages += ["asbuilt.catalogs"]

setup(packages=packages)
