"""PROTOCOL.md's worked example is what the encoder produces."""

from pathlib import Path

from firmware_bridge import protocol


def test_protocol_md_example_matches_the_encoder():
    doc = (Path(protocol.__file__).parent / "PROTOCOL.md").read_text()
    wire_line = next(line for line in doc.splitlines() if line.startswith("wire: 00 03"))
    wire = bytes.fromhex(wire_line.removeprefix("wire:"))
    assert wire == protocol.encode_sample(1, 5000, (0, 0, 4096), (4096, 0, 0))
