"""A client written from PROTOCOL.md's tables alone (none of the project's code: its own COBS,
CRC and field layouts) reads `quickjab bridge emulate` on a pty, on a clean link and with every
fault option, and its counts must equal the emulator's own report exactly."""

from __future__ import annotations

import os
import re
import struct
import subprocess
import sys
import time
import zlib
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]

# PROTOCOL.md: type -> CRC_EXTRA; header <BHIB; HELLO payload <HIHIBB (14 bytes)
CRC_EXTRA = {1: 0x3C, 2: 0xA7, 3: 0x51}
SAMPLE, HELLO, TEXT = 1, 2, 3
MAX_ENCODED = 214


def cobs_decode(enc: bytes) -> bytes | None:
    out = bytearray()
    i = 0
    while i < len(enc):
        code = enc[i]
        if code == 0 or i + code > len(enc):
            return None
        out += enc[i + 1 : i + code]
        i += code
        if code != 0xFF and i < len(enc):
            out.append(0)
    return bytes(out)


class Client:
    """PROTOCOL.md's receiver rules, written out again."""

    def __init__(self) -> None:
        self.buf = bytearray()
        self.bytes = 0
        self.good = {SAMPLE: 0, HELLO: 0, TEXT: 0}
        self.bad = 0  # segments rejected for any reason
        self.lost = 0
        self.seq_jumps = 0
        self.boots: list[int] = []
        self.last_seq: int | None = None
        self.ts_bits: int | None = None
        self.last_t: int | None = None
        self.time_backwards = 0

    def feed(self, data: bytes) -> None:
        self.bytes += len(data)
        for b in data:
            if b:
                self.buf.append(b)
                continue
            if self.buf:
                self.segment(bytes(self.buf))
            self.buf.clear()

    def segment(self, enc: bytes) -> None:
        body = cobs_decode(enc) if len(enc) <= MAX_ENCODED else None
        if body is None or len(body) < 12:
            self.bad += 1
            return
        ver, kind = body[0] >> 4, body[0] & 0x0F
        if ver != 1 or kind not in CRC_EXTRA:
            self.bad += 1
            return
        if zlib.crc32(body[:-4] + bytes([CRC_EXTRA[kind]])) != struct.unpack("<I", body[-4:])[0]:
            self.bad += 1
            return
        _, seq, t_us, flags = struct.unpack("<BHIB", body[:8])
        payload = body[8:-4]
        if flags & 0xF0 or (kind == TEXT and flags):  # TEXT frames carry flags 0
            self.bad += 1
            return
        sensors = (flags & 1) + (flags >> 1 & 1)
        if kind == SAMPLE and (not sensors or len(payload) != 2 * sensors * (6 if flags & 4 else 3)):
            self.bad += 1
            return
        if kind == HELLO:
            if len(payload) != 14:
                self.bad += 1
                return
            accel, gyro, rate, boot, ts_bits, _ = struct.unpack("<HIHIBB", payload)
            assert 8 <= ts_bits <= 32 and accel > 0 and rate > 0 and gyro > 0  # real scales in every HELLO
            if not self.boots or boot != self.boots[-1]:
                self.boots.append(boot)
                self.last_seq = self.last_t = None  # a new boot restarts the sequence and the clock
            self.ts_bits = ts_bits
        if self.last_seq is not None:
            gap = (seq - self.last_seq - 1) & 0xFFFF
            if gap >= 32768:
                self.seq_jumps += 1
            else:
                self.lost += gap
        self.last_seq = seq
        if self.ts_bits is not None:
            mask = (1 << self.ts_bits) - 1
            if self.last_t is not None and (t_us - self.last_t) & mask >= 1 << (self.ts_bits - 1):
                self.time_backwards += 1
            self.last_t = t_us & mask
        self.good[kind] += 1


def run_emulator(tmp_path: Path, *options: str) -> tuple[Client, dict[str, int]]:
    link = tmp_path / "bridge"
    emu = subprocess.Popen([sys.executable, "-m", "tools.cli", "bridge", "emulate", "--link", str(link), *options],
                           cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           env={**os.environ, "PYTHONPATH": str(REPO)})
    client = Client()
    try:
        emu.stdout.readline()  # port: ... (the link exists from now on)
        fd = -1
        while True:
            if fd < 0:
                if emu.poll() is not None:
                    break
                try:  # a replug: the link points at the new pty (never flushed: every byte counts)
                    # (the emulator keeps its end raw; setraw here would flush the queue)
                    fd = os.open(link, os.O_RDONLY | os.O_NOCTTY | os.O_NONBLOCK)
                except OSError:
                    time.sleep(0.005)
                    continue
            try:
                data = os.read(fd, 4096)
            except BlockingIOError:
                time.sleep(0.001)
                continue
            except OSError:
                data = b""
            if not data:  # the device end closed: an unplug, or the end of the run
                os.close(fd)
                fd = -1
                continue
            client.feed(data)
        _, err = emu.communicate(timeout=30)
    finally:
        if emu.poll() is None:
            emu.kill()
    assert emu.returncode == 0, err
    report = next(line for line in err.splitlines() if line.startswith("emulator:"))
    return client, {k: int(v) for k, v in re.findall(r"(\w+)=(\d+)", report)}


def test_clean_link_every_frame_accounted_for(tmp_path):
    client, emu = run_emulator(tmp_path, "--seconds", "2", "--ticks-start", str((1 << 30) - 1_000_000))
    assert emu["samples"] > 300 and emu["undelivered"] == 0
    assert client.bytes == emu["bytes"]
    assert (client.good[SAMPLE], client.good[HELLO], client.good[TEXT]) == (emu["samples"], emu["hellos"], emu["texts"])
    assert client.bad == client.lost == client.seq_jumps == client.time_backwards == 0  # across the 30-bit wrap
    assert len(client.boots) == 1


def test_every_fault_option_counts_agree_exactly(tmp_path):
    # fault times chosen so that no damaged frame is the first or last of a boot (a receiver
    # cannot see a gap there): flips every 0.43 s, drops every 0.55 s, reboot 2.3 s, unplug 3.6 s
    client, emu = run_emulator(
        tmp_path, "--seconds", "5", "--seed", "7", "--garbage-every", "0.3", "--garbage-len", "40",
        "--flip-every", "0.43", "--drop-every", "0.55", "--stall-at", "1.1", "--stall-s", "0.3",
        "--reboot-at", "2.3", "--unplug-at", "3.6", "--unplug-s", "0.4", "--ticks-start", "1073000000")
    print("client", client.good, "bad", client.bad, "lost", client.lost, "boots", len(client.boots), "| emulator", emu)
    assert emu["bit_flips"] >= 8 and emu["dropped_bytes"] >= 6 and emu["garbage_bursts"] >= 12
    assert emu["stalls"] == 1 and emu["reboots"] == 2 and emu["unplugs"] == 1
    assert client.bytes == emu["bytes"]
    assert (client.good[SAMPLE], client.good[HELLO], client.good[TEXT]) == (emu["samples"], emu["hellos"], emu["texts"])
    assert 0 < emu["broken"] <= emu["bit_flips"] + emu["dropped_bytes"]  # a frame may get both
    assert client.lost == emu["broken"] + emu["short_writes"]  # every lost frame is one the emulator damaged
    assert client.bad >= emu["broken"] + emu["garbage_bursts"]  # garbage and damaged frames: rejected, never taken
    assert len(client.boots) == 1 + emu["reboots"] and client.seq_jumps == 0
    assert client.time_backwards == 0
