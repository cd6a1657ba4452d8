"""The first bytes of each kind of file a command writes again and again (a screenshot, a plot, a
trace, the recognizer's events): what such an output may replace (engine.errors.refuse_other_kind).
An earlier file of its kind is replaced; a recording, an action or anything else found at the
path is not. The .npz and BVH heads live with their writers (engine.npz_files, game.bvh)."""

from __future__ import annotations

import re

# pygame.image.save writes PNG, JPEG, BMP or (any other suffix) TGA; matplotlib GIF, WebP, TIFF too
IMAGE_MAGIC = (b"\x89PNG\r\n\x1a\n", b"\xff\xd8\xff", b"BM", b"GIF8", b"RIFF", b"II*\x00", b"MM\x00*")
TGA_IMAGE_TYPES = (1, 2, 3, 9, 10, 11)  # colour-mapped, true-colour, grey; raw or run-length
DOCUMENT_MAGIC = (b"%PDF", b"%!PS", b"\xc5\xd0\xd3\xc6", b"\x1f\x8b")  # pdf, ps / eps (and binary eps), svgz
HEADLESS_PLOT_FORMATS = ("raw", "rgba")  # matplotlib's bare pixel buffers: is_pixels_head


def is_image_head(head: bytes) -> bool:
    """Whether a file's first bytes are an image's: PNG, JPEG, BMP, GIF, WebP, TIFF, or a TGA
    header (no magic number: its colour-map flag 0 or 1 and a known image type, which no text
    file's second and third bytes are)."""
    if head.startswith(IMAGE_MAGIC):
        return True
    return len(head) >= 18 and head[1] in (0, 1) and head[2] in TGA_IMAGE_TYPES


def is_plot_head(head: bytes) -> bool:
    """An image's (AVIF too: an ISO media file, `ftyp` at its 5th byte), or a document matplotlib
    writes (PDF, PostScript, SVG, gzipped SVG). Its raw RGBA buffers have no head: plot_file does
    not ask (HEADLESS_PLOT_FORMATS)."""
    return (is_image_head(head) or head.startswith(DOCUMENT_MAGIC) or head[4:8] == b"ftyp"
            or _text(head).startswith((b"<?xml", b"<svg")))


def is_pixels_head(head: bytes) -> bool:
    """Whether a file's first bytes may be matplotlib's raw RGBA pixels (no head of their own: a
    plot's white background is 0xFF bytes): neither text (a recording, a trace, an action, event
    lines) nor a zip archive (templates, a graph)."""
    if head.startswith(b"PK"):
        return False
    try:
        head.decode("utf-8")
    except UnicodeDecodeError as exc:
        return exc.start < len(head) - 3  # not a character cut off by the head's end
    return False


def _text(head: bytes) -> bytes:
    """A text head without its UTF-8 byte-order mark and leading white space."""
    return head.removeprefix(b"\xef\xbb\xbf").lstrip()


def is_trace_head(head: bytes) -> bool:
    """Whether a file's first bytes are a Chrome trace's: the object form the loop writes
    (`{"traceEvents": ...`) or the bare array of events another tool may have left."""
    return re.match(rb'(\{\s*"traceEvents"|\[\s*[{\]])', _text(head)) is not None


def is_events_head(head: bytes) -> bool:
    """Whether a file's first bytes are the recognizer's JSON lines (`recognize -o`: each line
    an object whose first key is "event"; docs/formats.md)."""
    return re.match(rb'\{\s*"event"', _text(head)) is not None
