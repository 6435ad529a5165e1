"""pip install --no-build-isolation ./python (docs/python.md): the package meso and its cffi
extension, built against libmeso.so (meso_build.py says where it is looked for)."""

from setuptools import setup

setup(
    name="meso",
    version="0.1.0",
    description="meso from Python: scenes, renders and comparisons as NumPy arrays",
    packages=["meso"],
    python_requires=">=3.9",
    setup_requires=["cffi>=1.15"],
    install_requires=["cffi>=1.15", "numpy"],
    cffi_modules=["meso_build.py:ffibuilder"],
    zip_safe=False,
)
