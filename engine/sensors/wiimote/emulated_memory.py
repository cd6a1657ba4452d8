"""The emulated remote's memory: its EEPROM (Wiimote calibration at 0x16, a copy at 0x20) and
the Nunchuk's i2c register file (slave 0x52: data at 0x00, calibration at 0x20, init at
0xF0/0xFB, ID at 0xFA), answering the host's 0x16 writes and 0x17 reads as a real remote does."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from engine.sensors.wiimote import protocol as p

EEPROM_SIZE = 0x1700  # Dolphin EEPROM_FREE_SIZE: reads past it fail with error 8
EXT_SLAVE = 0x52  # the extension's i2c address (0xA4 >> 1)
CHUNK_GAP_S = 0.005  # between successive 0x21 replies of one read


def _zero_key_encrypted(data: bytes) -> bytes:
    """What an uninitialised Nunchuk's registers read as: encrypted with the all-zero key, the
    inverse of WiiBrew's decryption (x ^ 0x17) + 0x17 (its ID 00 00 reads FE FE)."""
    return bytes(((b - 0x17) & 0xFF) ^ 0x17 for b in data)


class EmulatedMemory:
    """EEPROM and extension registers, and how far the extension's init got (`ext_stage`).
    `clone` "" is genuine; "zeros" or any other value (garbage, drawn from `rng`) gives an
    unreadable Nunchuk calibration, the latter also a bad EEPROM block at 0x16. Malformed
    writes and reads are counted through `count(key)`."""

    def __init__(self, wiimote_cal: p.Calibration, nunchuk_cal: p.Calibration, clone: str,
                 rng: np.random.Generator, count: Callable[[str], None]) -> None:
        self.count = count
        self.ext_stage = 0  # 1 after 0x55 -> F0; 2 (plain data) after 0x00 -> FB
        self.read_busy_until = -1.0  # a read's replies go out until then
        self.eeprom = bytearray(EEPROM_SIZE)
        good = p.encode_calibration(wiimote_cal)
        self.eeprom[0x16:0x20] = good
        self.eeprom[0x20:0x2A] = good
        self.ext_regs = bytearray(256)
        self.ext_regs[0xFA:0x100] = bytes([0x00, 0x00, 0xA4, 0x20, 0x00, 0x00])
        if clone in ("zeros",):
            cal_block = bytes(16)
        elif clone:
            cal_block = bytes(rng.integers(0, 256, 16, dtype=np.uint8))
            if p.parse_nunchuk_calibration(cal_block) is not None:  # astronomically unlikely
                cal_block = bytes(16)
            bad = bytearray(good)
            bad[9] ^= 0xFF
            self.eeprom[0x16:0x20] = bad
        else:
            cal_block = p.encode_nunchuk_calibration(nunchuk_cal)
        self.ext_regs[0x20:0x30] = cal_block
        self.ext_regs[0x30:0x40] = cal_block

    def ext_bytes(self, plugged: bool) -> bytes:
        """The 21 extension bytes of a data report."""
        if not plugged:
            return bytes(21)
        data = bytes(self.ext_regs[0:21])
        if self.ext_stage < 2:  # not initialised: what comes out is encrypted
            data = _zero_key_encrypted(data)
        return data

    def write(self, data: bytes, plugged: bool) -> int | None:
        """A 0x16 write report: the error code to ack, or None when it is ignored."""
        if len(data) < 6:
            self.count("short_output")
            return None
        space = (data[1] >> 2) & 0x3
        address = data[3] << 8 | data[4]
        size = data[5]
        payload = data[6 : 6 + size]
        if size == 0 or size > 16 or len(payload) < size:
            self.count("invalid_write")  # a real remote silently ignores it
            return None
        error = p.ERR_OK
        if space == 0:
            if address + size > EEPROM_SIZE:
                error = p.ERR_INVALID_ADDRESS
            else:
                self.eeprom[address : address + size] = payload
        elif space in (1, 2):
            slave = data[2] >> 1
            if slave == EXT_SLAVE and plugged:
                reg = address & 0xFF
                for i, b in enumerate(payload):
                    self._ext_register_write((reg + i) & 0xFF, b)
            elif slave == EXT_SLAVE:
                error = p.ERR_NACK
            # other slaves (speaker 0x51, camera 0x58) accept and are not modelled
        else:
            error = p.ERR_INVALID_SPACE
        return error

    def _ext_register_write(self, reg: int, value: int) -> None:
        if reg == 0xF0:
            self.ext_stage = 1 if value == 0x55 else 0
            return
        if reg == 0xFB:
            if self.ext_stage >= 1 and value == 0x00:
                self.ext_stage = 2
            return
        if reg >= 0xFA:
            return  # the ID is read-only
        self.ext_regs[reg] = value

    def reset_link(self) -> None:
        """A new connection: the extension uninitialised, no read under way."""
        self.ext_stage = 0
        self.read_busy_until = -1.0

    def read(self, data: bytes, plugged: bool, now: float, latency: float) -> list[tuple[bytes, float]]:
        """A 0x17 read report at `now`: its 0x21 replies with their times, from `latency` on.
        A read during a read is refused with a busy ack (0x22, error 4) and the first goes on,
        as Dolphin's HandleReadData says a real remote does."""
        if len(data) < 7:
            self.count("short_output")
            return []
        t = now + latency
        if now < self.read_busy_until:
            self.count("read_busy")
            return [(bytes([p.IN_ACK, 0, 0, p.OUT_READ_MEMORY, p.ERR_BUSY]), t)]
        space = (data[1] >> 2) & 0x3
        address = data[3] << 8 | data[4]
        size = data[5] << 8 | data[6]
        if size == 0:
            return []
        replies: list[tuple[bytes, float]] = []

        def reply(error: int, addr: int, chunk: bytes, at: float) -> None:
            n = len(chunk) if not error else 16  # errors report size nibble 0xF (Dolphin)
            replies.append((bytes([p.IN_READ_REPLY, 0, 0, (n - 1) << 4 | error, addr >> 8 & 0xFF, addr & 0xFF]) + chunk.ljust(16, b"\0"), at))

        if space == 0:
            if address + size > EEPROM_SIZE:
                reply(p.ERR_INVALID_ADDRESS, address, b"", t)
                return replies
            source = bytes(self.eeprom)
        elif space in (1, 2) and data[2] >> 1 == EXT_SLAVE and plugged:
            source = bytes(self.ext_regs)
            if self.ext_stage < 2:  # the ID too: Dolphin's real-remote code cannot identify
                source = _zero_key_encrypted(source)  # an uninitialised extension
        else:
            reply(p.ERR_NACK if space in (1, 2) else p.ERR_INVALID_SPACE, address, b"", t)
            return replies
        done = 0
        while done < size:
            n = min(16, size - done)
            a = address + done
            if len(source) == 256:  # the i2c register file wraps
                chunk = bytes(source[(a + i) & 0xFF] for i in range(n))
            else:
                chunk = source[a : a + n]
            reply(p.ERR_OK, a & 0xFFFF, chunk, t)
            done += n
            t += CHUNK_GAP_S
        self.read_busy_until = t
        return replies
