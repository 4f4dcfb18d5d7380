"""The XML writer of conversions: attribute quoting against the standard library's, and the
fragment's structure (nested BSDFs as elements), without Mitsuba."""

import xml.etree.ElementTree as ET
from xml.sax.saxutils import quoteattr as stdlib_quoteattr

import pytest

from plausible.conversion import mitsuba_xml, quoteattr


@pytest.mark.parametrize("text", ["plain", "a&b<c>", "line\nbreak\ttab", "both \" and '"])
def test_quoteattr_escapes_as_the_standard_library(text):
    assert quoteattr(text) == stdlib_quoteattr(text)


def test_an_attribute_with_a_double_quote_reads_back_as_written():
    # the standard library switches to single quotes here; ours escapes: both read back alike
    text = 'say "hi"'
    assert ET.fromstring("<a v=" + quoteattr(text) + "/>").get("v") == text


def test_a_nested_bsdf_is_an_element_and_colours_are_rgb():
    d = {"type": "blendbsdf", "weight": 0.25, "bsdf_0": {"type": "diffuse", "reflectance": {"type": "rgb",
                                                                                            "value": [0.1, 0.2, 0.3]}},
         "bsdf_1": {"type": "roughconductor", "material": "none", "alpha": 0.2}}
    root = ET.fromstring(mitsuba_xml({"a&b": d}))
    (bsdf,) = root
    assert (bsdf.get("type"), bsdf.get("id")) == ("blendbsdf", "a&b")
    kids = [(c.tag, c.get("type"), c.get("name")) for c in bsdf]
    assert kids == [("float", None, "weight"), ("bsdf", "diffuse", "bsdf_0"), ("bsdf", "roughconductor", "bsdf_1")]
    assert bsdf[1][0].attrib == {"name": "reflectance", "value": "0.1, 0.2, 0.3"}
