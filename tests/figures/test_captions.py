"""Every caption of a paper's figure quotes the paper exactly: each fragment (the text
between the editorial brackets ``[Sec. 2:]``, the quotation marks and `` ... ``) is
found in the text of one of the four papers, compared without white space, mathematical
markup and the paper text's hyphenation at line ends.  The papers are not shipped (their
licences); the test runs where they are (``PLAUSIBLE_PAPERS`` or ``../shared/papers``)."""

import os
import re
from pathlib import Path

import pytest

from plausible import figures

ROOT = Path(__file__).resolve().parents[2]
CANDIDATES = [Path(os.environ["PLAUSIBLE_PAPERS"])] if "PLAUSIBLE_PAPERS" in os.environ else []
CANDIDATES += [ROOT.parent / "shared" / "papers", ROOT.parent.parent / "shared" / "papers"]
PAPERS = next((p for p in CANDIDATES if p.is_dir() and list(p.glob("*.txt"))), None)

#: How the papers' text files (OCR) render what the captions write correctly.
OCR = {"σ0": "oo", "τ": "7", "c_n <= (n + 2)/2π": "¢, < (n + 2)/27", "Lambertian sphere": "Lamertian sphere"}


def _squash(text: str) -> str:
    text = re.sub(r"<\|[^|]*\|>", " ", text)
    for a, b in (("\u2019", "'"), ("\u2018", "'"), ("\u201c", ""), ("\u201d", ""), ('"', "")):
        text = text.replace(a, b)
    return re.sub(r"[\s$_\\{}*]", "", text).lower()     # * : the italics of the text files


def _paper_texts():
    out = []
    for p in sorted(PAPERS.glob("*.txt")):
        raw = p.read_text()
        out += [_squash(raw), _squash(re.sub(r"-\s*\n\s*", "", raw))]   # hyphenated line ends
    return out


def fragments(caption: str) -> list[str]:
    """The quoted pieces of a caption: split at editorial brackets, quotation marks and ' ... '."""
    for good, ocr in OCR.items():
        caption = caption.replace(good, ocr)
    text = re.sub(r"\[[^\]]*\]", "|", caption)
    parts = re.split(r"[\u201c\u201d|]| \.\.\. ", text)
    return [f.strip(" .") for f in parts if len(f.strip(" .")) >= 12]


def missing(caption: str, texts) -> list[str]:
    return [f for f in fragments(caption) if not any(_squash(f) in t for t in texts)]


PAPER_FIGURES = [n for n in figures.names() if figures.get(n).source.startswith(("Neumann", "Ashikhmin", "Modified"))]


@pytest.mark.skipif(PAPERS is None, reason="the papers' text is not available here")
@pytest.mark.parametrize("name", PAPER_FIGURES)
def test_caption_quotes_the_paper(name):
    assert fragments(figures.get(name).caption), name
    assert missing(figures.get(name).caption, _paper_texts()) == []


@pytest.mark.skipif(PAPERS is None, reason="the papers' text is not available here")
def test_a_misquoted_caption_is_caught():
    texts = _paper_texts()
    good = figures.get("neumann-fig5").caption
    assert missing(good, texts) == []
    assert missing(good.replace("below the constant 1", "at the constant 1"), texts)
    assert missing(good.replace("(n = 20)", "(n = 30)"), texts)
