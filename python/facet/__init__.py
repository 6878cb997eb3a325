"""Facet: microfacet materials compiled to fast, exact kernels.

    import facet, numpy as np
    k = facet.compile("materials/gold_ggx.mat")            # or text="material m { ... }"
    rgb = k.eval(wi, wo, roughness=0.3)                    # wi, wo: (N, 3) or (3, N)
    wi, pdf, weight = k.sample(wo, u)                      # u: uniform numbers in [0, 1)
    p = k.pdf(wi, wo)

compile(path=None, text=None, material=None, **options) takes the options of
SPEC 4 as keywords: backend ("simd", "scalar", "interp"), math ("exact",
"fast"), tolerance, width (4, 8, 16), cache ("on", "off", "memory"),
codegen ("tiered", "quick", "optimized"), float_first (bool), assume
("unit", "none"), transport ("radiance", "importance": the eta^2 convention of
refracting lobes) and set={"name": value} (rgb values as 3-tuples). A
mistake in the material raises MaterialError (file, line, column, message);
a bad option raises ValueError or TypeError.

Directions are (N, 3) or (3, N) arrays, or one direction of shape (3,) (a
(3, 3) array is read as (N, 3)); results have the layout of the first
direction argument. A (3, N) float32 C-contiguous array is read in place;
any other real array goes through one conversion (numpy.ascontiguousarray).
Inputs are keywords: a number, or one value per lane; rgb inputs a 3-tuple
or an (N, 3) array. Compiled kernels compute in float32; backend="interp"
is the double reference interpreter and returns float64. With status=True,
eval also returns the per-lane invalid flags and sample / pdf the number of
invalid lanes (a non-finite or non-unit direction, u outside [0, 1), a
non-finite input: their outputs are 0). Batch calls release the GIL; a
kernel may be used from many threads at once.

Kernels are cached as the C API's are (FACET_CACHE_DIR, else
$XDG_CACHE_HOME/facet or ~/.cache/facet, trusted only when owned by you).
"""

import collections
import os

from . import _facet

__all__ = ["compile", "check", "Kernel", "MaterialError", "Diagnostic", "Input"]

Kernel = _facet.Kernel


class Diagnostic(collections.namedtuple("Diagnostic", "file line column message")):
    """One error in a material: where (line and column 1-based; 0 when the
    error is about the whole file) and what."""

    __slots__ = ()

    def __str__(self):
        where = self.file if self.line == 0 else f"{self.file}:{self.line}:{self.column}"
        return f"{where}: error: {self.message}"


Input = collections.namedtuple("Input", "name type default range")
Input.__doc__ = "A material input: name, 'float' or 'rgb', its default, and (lo, hi) or None."


class MaterialError(Exception):
    """A material that does not compile: file, line, column and message of the
    first error; every error in .diagnostics."""

    def __init__(self, diagnostics):
        self.diagnostics = list(diagnostics)
        first = self.diagnostics[0]
        self.file, self.line, self.column, self.message = first
        super().__init__("\n".join(str(d) for d in self.diagnostics))


def _inputs(kernel):
    return [Input(*t) for t in kernel._inputs]


Kernel.inputs = property(_inputs, doc="The material's inputs (Input tuples), in slot order.")

# Options whose values are words; the library checks the words
# (CompileOptions::parse), so that its choices are written down once.
_WORD_OPTIONS = ("backend", "math", "cache", "codegen", "assume", "transport")


def _number(name, value):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TypeError(f"compile(): {name}: expected a number, got {type(value).__name__}")
    return repr(float(value))


def _option_string(options):
    items = []
    for key, value in options.items():
        if key in _WORD_OPTIONS:
            if not isinstance(value, str):
                raise TypeError(f"compile(): {key}: expected a str")
            if ";" in value:
                raise ValueError(f"compile(): {key}={value!r}: ';' separates options")
            items.append(f"{key}={value}")
        elif key == "width":
            if isinstance(value, bool) or not isinstance(value, int):
                raise TypeError("compile(): width: expected an int (4, 8 or 16)")
            items.append(f"width={value}")
        elif key == "tolerance":
            items.append(f"tolerance={_number(key, value)}")
        elif key == "float_first":
            if not isinstance(value, bool):
                raise TypeError("compile(): float_first: expected True or False")
            items.append(f"float_first={'on' if value else 'off'}")
        elif key == "set":
            if not isinstance(value, dict):
                raise TypeError("compile(): set: expected a dict of input names to values")
            for name, v in value.items():
                if not isinstance(name, str) or not name.isidentifier():
                    raise ValueError(f"compile(): set: {name!r} is not an input name")
                if isinstance(v, (tuple, list)):
                    if len(v) != 3:
                        raise ValueError(f"compile(): set: {name}: expected a number or an (r, g, b) triple")
                    text = ",".join(_number(f"set {name}", x) for x in v)
                else:
                    text = _number(f"set {name}", v)
                items.append(f"set.{name}={text}")
        else:
            known = ", ".join(list(_WORD_OPTIONS) + ["width", "tolerance", "float_first", "set"])
            raise TypeError(f"compile() got an unexpected option {key!r} (options: {known})")
    return ";".join(items)


def compile(path=None, text=None, material=None, **options):
    """Compiles material `material` (default: the first) of a file or a text.

    Returns a Kernel; raises MaterialError for a mistake in the material,
    FileNotFoundError for a missing file, TypeError / ValueError for bad
    options."""
    if (path is None) == (text is None):
        raise TypeError("compile(): give exactly one of path= and text=")
    if text is not None and not isinstance(text, str):
        raise TypeError("compile(): text: expected a str")
    if path is not None:
        path = os.fspath(path)
        if text is None and not os.path.exists(path):
            raise FileNotFoundError(2, "no such material file", path)
    if material is not None and not isinstance(material, str):
        raise TypeError("compile(): material: expected the name of a material (str)")
    kernel, diagnostics, problem = _facet.compile(path, text, material or "", _option_string(options))
    if problem:
        raise ValueError(f"compile(): {problem}")
    if kernel is None:
        raise MaterialError(Diagnostic(*d) for d in diagnostics)
    return kernel


def check(source=None, *, path=None, text=None):
    """The diagnostics (a list of Diagnostic, empty when it is fine) of a
    material file or text. `source` is read as text when it holds a '{' or a
    newline, else as a path."""
    given = [x is not None for x in (source, path, text)]
    if sum(given) != 1:
        raise TypeError("check(): give one of source, path= and text=")
    if source is not None:
        source = os.fspath(source)
        if "{" in source or "\n" in source:
            text = source
        else:
            path = source
    return [Diagnostic(*d) for d in _facet.check(path, text)]
