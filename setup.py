"""Package discovery for the fixed repository layout (everything else is in pyproject.toml).

The top-level folders drivers/ and catalogs/ install as the subpackages asbuilt.drivers and
asbuilt.catalogs (see ``package-dir`` in pyproject.toml); setuptools' automatic discovery only
finds folders named after their package, so list them here.
"""

from setuptools import find_namespace_packages, setup

# Namespace discovery so that the data folders asbuilt/data and asbuilt/schemas are packages too.
packages = find_namespace_packages(
    ".", include=["asbuilt", "asbuilt.*"], exclude=["*.__pycache__", "*.__pycache__.*"]
)
packages += ["asbuilt.drivers"] + [
    f"asbuilt.drivers.{p}"
    for p in find_namespace_packages("drivers", exclude=["__pycache__", "*.__pycache__"])
]
packages += ["asbuilt.catalogs"]

setup(packages=packages)
