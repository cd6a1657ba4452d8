# ruff: noqa: UP031  (%-formatting: the same code must run on MicroPython)
# The serial bridge wire protocol, v1 (PROTOCOL.md). This ONE file runs unchanged on CPython
# and on MicroPython (copied to the board as protocol.py), so it keeps to what both have:
# struct, binascii.crc32, %-formatting, plain classes; no f-strings, typing, dataclasses,
# int.to_bytes or micropython.const. Type hints live in comments only.
#
# Frame on the wire:  0x00, COBS(body), 0x00      (a delimiter on both sides)
# body (little endian): ver_type:u8 seq:u16 t_us:u32 flags:u8 payload crc32:u32
# crc32 = binascii.crc32(body_without_crc + bytes([CRC_EXTRA[type]]))

import binascii
import struct

VERSION = 1

SAMPLE = 1
HELLO = 2
TEXT = 3
TYPE_NAMES = {SAMPLE: "sample", HELLO: "hello", TEXT: "text"}

# One fixed byte per message type, appended to the CRC input only (MAVLink's CRC_EXTRA): a
# sender and receiver that disagree on a type's layout fail every CRC instead of misreading.
CRC_EXTRA = {SAMPLE: 0x3C, HELLO: 0xA7, TEXT: 0x51}

# flags (header byte 7); any other bit set makes the frame malformed
FLAG_SENSOR_A = 0x01  # right hand (rx,ry,rz)
FLAG_SENSOR_B = 0x02  # left hand (lx,ly,lz)
FLAG_GYRO = 0x04  # SAMPLE carries gyro after each sensor's accel
FLAG_OVERRUN = 0x08  # the device dropped output since the last frame (host not reading)
FLAGS_KNOWN = 0x0F
FLAGS_SENSORS = FLAG_SENSOR_A | FLAG_SENSOR_B  # the bits that say which sensors a frame carries

IMU_UNKNOWN = 0
IMU_MPU6050 = 1
IMU_LSM6DS3 = 2
IMU_SIMULATED = 3

HEADER = "<BHIB"  # ver_type, seq, t_us, flags
HEADER_SIZE = 8
CRC_SIZE = 4
HELLO_FMT = "<HIHIBB"  # accel_lsb_per_g, gyro_mlsb_per_dps, rate_hz, boot_id, ts_bits, imu_kind
HELLO_SIZE = 14
MAX_TEXT = 200
MAX_BODY = HEADER_SIZE + MAX_TEXT + CRC_SIZE  # 212: the largest valid body
MAX_ENCODED = MAX_BODY + 2  # COBS adds a code byte per 254 bytes (one here: 213 at most), plus a byte of slack

# Host to device: this one byte asks for a HELLO now (a host that just opened the port need not
# wait for the next one-a-second HELLO). Devices ignore any other byte.
HELLO_REQUEST = b"?"

SEQ_MASK = 0xFFFF
T_MASK = 0xFFFFFFFF


def cobs_encode(data):
    # type: (bytes) -> bytes
    """Consistent Overhead Byte Stuffing: the result contains no 0x00 byte."""
    data = bytes(data)
    out = bytearray()
    parts = data.split(b"\x00")
    last = len(parts) - 1
    for i in range(len(parts)):
        part = parts[i]
        while len(part) >= 254:
            out.append(255)
            out.extend(part[:254])
            part = part[254:]
            if not part and i == last:
                return bytes(out)  # canonical: no empty block after a full one at the end
        out.append(len(part) + 1)
        out.extend(part)
    return bytes(out)


def cobs_decode(enc):
    # type: (bytes) -> bytes | None
    """The inverse of cobs_encode; None when `enc` is not a valid encoding."""
    blocks = []
    i = 0
    n = len(enc)
    while i < n:
        code = enc[i]
        if code == 0 or i + code > n:
            return None
        if code == 255:
            return _cobs_decode_long(enc)
        blocks.append(enc[i + 1 : i + code])
        i += code
    # without a full 254-byte block every block but the last is followed by a zero
    return b"\x00".join(blocks)


def _cobs_decode_long(enc):
    out = bytearray()
    i = 0
    n = len(enc)
    while i < n:
        code = enc[i]
        if code == 0 or i + code > n:
            return None
        out.extend(enc[i + 1 : i + code])
        i += code
        if code != 255 and i < n:
            out.append(0)
    return bytes(out)


def _crc(msg_type, body):
    return binascii.crc32(bytes((CRC_EXTRA[msg_type],)), binascii.crc32(body)) & 0xFFFFFFFF


def encode_frame(msg_type, seq, t_us, flags, payload):
    # type: (int, int, int, int, bytes) -> bytes
    """A whole frame for the wire, delimiters included."""
    body = struct.pack(HEADER, (VERSION << 4) | msg_type, seq & SEQ_MASK, t_us & T_MASK, flags) + payload
    body += struct.pack("<I", _crc(msg_type, body))
    return b"\x00" + cobs_encode(body) + b"\x00"


def _clamp16(v):
    v = int(v)
    if v > 32767:
        return 32767
    if v < -32768:
        return -32768
    return v


def sample_flags(accel_a, accel_b, gyro):
    f = 0
    if accel_a is not None:
        f |= FLAG_SENSOR_A
    if accel_b is not None:
        f |= FLAG_SENSOR_B
    if gyro:
        f |= FLAG_GYRO
    return f


def encode_sample(seq, t_us, accel_a, accel_b=None, gyro_a=None, gyro_b=None, overrun=False):
    # type: (int, int, tuple | None, tuple | None, tuple | None, tuple | None, bool) -> bytes
    """SAMPLE: raw int16 accel x,y,z per present sensor, each followed by gyro x,y,z when given
    (gyro is all or nothing: give gyro_a and gyro_b for every present sensor, or neither)."""
    gyro = gyro_a is not None or gyro_b is not None
    flags = sample_flags(accel_a, accel_b, gyro)
    if overrun:
        flags |= FLAG_OVERRUN
    vals = []
    for acc, gyr in ((accel_a, gyro_a), (accel_b, gyro_b)):
        if acc is None:
            continue
        vals.extend(acc)
        if gyro:
            vals.extend(gyr if gyr is not None else (0, 0, 0))
    payload = struct.pack("<%dh" % len(vals), *[_clamp16(v) for v in vals])
    return encode_frame(SAMPLE, seq, t_us, flags, payload)


def encode_hello(seq, t_us, boot_id, rate_hz, accel_lsb_per_g, gyro_mlsb_per_dps, ts_bits, imu_kind, flags):
    # type: (int, int, int, int, int, int, int, int, int) -> bytes
    """HELLO, at boot and every second: scales, rate, boot_id, timestamp width; flags say which
    sensors are present and whether SAMPLEs carry gyro."""
    payload = struct.pack(
        HELLO_FMT, accel_lsb_per_g, gyro_mlsb_per_dps, rate_hz, boot_id & 0xFFFFFFFF, ts_bits, imu_kind
    )
    return encode_frame(HELLO, seq, t_us, flags & FLAGS_KNOWN & ~FLAG_OVERRUN, payload)


def encode_text(seq, t_us, text):
    # type: (int, int, str | bytes) -> bytes
    """TEXT: a UTF-8 log line from the device (at most MAX_TEXT bytes; longer is cut, between
    two characters: never inside one, which would leave the payload no longer UTF-8)."""
    if isinstance(text, str):
        text = text.encode()
    text = bytes(text)
    n = len(text)
    if n > MAX_TEXT:
        n = MAX_TEXT
        while n > 0 and text[n] & 0xC0 == 0x80:  # text[n] continues a character: cut before it
            n -= 1
    return encode_frame(TEXT, seq, t_us, 0, text[:n])


def sample_values_per_sensor(flags):
    # type: (int) -> int
    return 6 if flags & FLAG_GYRO else 3


def sensor_count(flags):
    # type: (int) -> int
    """How many sensors the flags announce (0, 1 or 2)."""
    return (1 if flags & FLAG_SENSOR_A else 0) + (1 if flags & FLAG_SENSOR_B else 0)


def sample_payload_size(flags):
    # type: (int) -> int
    return 2 * sensor_count(flags) * sample_values_per_sensor(flags)


class Frame:
    """One decoded, CRC-checked frame."""

    def __init__(self, msg_type, seq, t_us, flags, payload):
        self.msg_type = msg_type
        self.seq = seq
        self.t_us = t_us
        self.flags = flags
        self.payload = payload
        self.jump = False  # set by Decoder: the sequence jumped back (a reboot without HELLO)

    def values(self):
        # type: () -> tuple
        """SAMPLE: the raw int16 values in wire order."""
        return struct.unpack("<%dh" % (len(self.payload) // 2), self.payload)

    def key(self):
        return (self.msg_type, self.seq, self.t_us, self.flags, self.payload)

    def __eq__(self, other):
        return isinstance(other, Frame) and self.key() == other.key()

    def __hash__(self):
        return hash(self.key())

    def __repr__(self):
        return "Frame(%s seq=%d t_us=%d flags=0x%02x %d bytes)" % (
            TYPE_NAMES.get(self.msg_type, "?"), self.seq, self.t_us, self.flags, len(self.payload))


class Hello:
    """The fields of a HELLO frame."""

    def __init__(self, frame):
        (self.accel_lsb_per_g, self.gyro_mlsb_per_dps, self.rate_hz, self.boot_id,
         self.ts_bits, self.imu_kind) = struct.unpack(HELLO_FMT, frame.payload)
        self.flags = frame.flags
        self.sensors = sensor_count(frame.flags)


def hello_problem(payload, flags):
    # type: (bytes, int) -> str | None
    """Why a HELLO payload of the right size is malformed (PROTOCOL.md), or None: every field
    must make sense, because the host divides by the scales and sizes its clock by ts_bits."""
    accel, gyro, rate, _, ts_bits, _ = struct.unpack(HELLO_FMT, payload)
    if not 8 <= ts_bits <= 32:
        return "ts_bits %d outside 8..32" % ts_bits
    if accel == 0:
        return "accel_lsb_per_g is 0"
    if gyro == 0 and flags & FLAG_GYRO:
        return "gyro_mlsb_per_dps is 0 with GYRO set"
    if rate == 0:
        return "rate_hz is 0"
    if flags & FLAG_OVERRUN:
        return "OVERRUN set on a HELLO"
    return None


def hello_rejection(body):
    # type: (bytes) -> str
    """Why a HELLO body that passed its CRC was rejected as malformed (PROTOCOL.md)."""
    payload = body[HEADER_SIZE:len(body) - CRC_SIZE]
    if len(payload) != HELLO_SIZE:
        return "a payload of %d bytes, not %d" % (len(payload), HELLO_SIZE)
    if body[7] & ~FLAGS_KNOWN:
        return "flags 0x%02x: bits 4-7 must be 0" % body[7]
    return hello_problem(payload, body[7]) or "?"


def clock_reach(ts_bits, rate_hz):
    # type: (int, int) -> float
    """How many sample periods half the device clock's period spans: how far apart in time two
    frames can be and still be ordered by t_us, which the host unwraps within half a period."""
    return (1 << (ts_bits - 1)) * rate_hz / 1000000


def narrow_clock(ts_bits, rate_hz):
    # type: (int, int) -> bool
    """t_us wraps within two sample periods: a host cannot tell its wraps apart, and its sample
    times come out wrong (PROTOCOL.md, HELLO: a valid HELLO, counted as `narrow_clock`)."""
    return clock_reach(ts_bits, rate_hz) <= 1


def parse_body(body):
    # type: (bytes) -> tuple
    """(Frame, None) for a valid body, or (None, counter_name) saying why it was rejected."""
    if len(body) < HEADER_SIZE + CRC_SIZE:
        return None, "runts"
    ver_type = body[0]
    msg_type = ver_type & 0x0F
    if ver_type >> 4 != VERSION or msg_type not in CRC_EXTRA:
        return None, "unknown_type"
    n = len(body) - CRC_SIZE
    if struct.unpack("<I", body[n:])[0] != _crc(msg_type, body[:n]):
        return None, "crc_errors"
    _, seq, t_us, flags = struct.unpack(HEADER, body[:HEADER_SIZE])
    payload = body[HEADER_SIZE:n]
    if flags & ~FLAGS_KNOWN:
        return None, "malformed"
    if msg_type == SAMPLE:
        if not flags & FLAGS_SENSORS or len(payload) != sample_payload_size(flags):
            return None, "malformed"
    elif msg_type == HELLO:
        if len(payload) != HELLO_SIZE or hello_problem(payload, flags) is not None:
            return None, "malformed"
    elif flags or len(payload) > MAX_TEXT:  # TEXT frames carry flags 0 (PROTOCOL.md)
        return None, "malformed"
    return Frame(msg_type, seq, t_us, flags, payload), None


COUNTERS = ("frames_ok", "crc_errors", "cobs_errors", "oversize", "runts", "unknown_type",
            "malformed", "lost", "reboots", "seq_jumps", "replays", "replays_ahead", "resyncs", "bytes_in")

SEQ_WINDOW = 0x8000  # a seq up to this far behind the last one is a repeat; further is a jump
OLD_BOOTS = 8  # boot ids remembered: a HELLO of an earlier boot is a replay, not a reboot


class Decoder:
    """Streaming decoder: feed bytes in any chunking, get whole frames back. Never raises.

    Counts (attributes, see COUNTERS): frames_ok, crc_errors, cobs_errors, oversize (a run of
    bytes without a delimiter longer than any frame), runts (too short for a header and CRC),
    unknown_type, malformed (CRC ok but a layout v1 does not allow), lost (frames missing by
    sequence number), reboots (HELLO with a new boot_id), seq_jumps (a backwards sequence jump
    not explained by a HELLO: a reboot whose HELLO was lost), replays (a frame whose seq this
    boot already delivered, or a HELLO of an earlier boot: dropped), replays_ahead (of those, the
    ones whose t_us is later than the last delivered frame's: what a host that stopped reading
    for 32768 frames or more sees until the board's next HELLO), resyncs (a HELLO of this boot
    behind in seq but ahead in t_us: the board's own word on where it is, so the sequence check
    goes on from it), bytes_in. `replay_run`: replays since the last delivered frame.
    """

    def __init__(self):
        for name in COUNTERS:
            setattr(self, name, 0)
        self._buf = b""
        self._skipping = False  # inside an oversize run: drop until the next delimiter
        self.last_seq = None
        self.boot_id = None
        self.hello = None  # the last Hello seen
        self.bad_hello = None  # why the last HELLO counted as malformed was (hello_rejection)
        self.old_boots = []  # boot ids before the current one, newest last
        self._headless_boot = False  # a seq_jump started a boot whose HELLO has not come yet
        self._old_seen = None  # meanwhile, the seq values the boot before it delivered
        # seen[s] is 1 once this boot delivered seq s (PROTOCOL.md: "this boot already delivered")
        self._seen = bytearray(SEQ_MASK + 1)
        self._resynced = False  # a HELLO resynced this boot's sequence check (`_restart_seq`)
        self.last_t = None  # t_us of the last delivered frame
        self.replay_run = 0  # frames dropped as replays since the last delivered one

    def resync(self):
        """Forget the unfinished frame and the sequence position (after a reconnect), keeping
        the counters and the boot_id."""
        self._buf = b""
        self._skipping = False
        self.last_seq = None

    def counts(self):
        # type: () -> dict
        d = {}
        for name in COUNTERS:
            d[name] = getattr(self, name)
        return d

    def feed(self, data):
        # type: (bytes) -> list
        """Decode what `data` completes; keeps any unfinished frame for the next call."""
        out = []
        try:
            self._feed(bytes(data), out)
        except Exception:  # never raises: a bug here must not stop the game loop
            self.malformed += 1
            self._buf = b""
            self._skipping = False
        return out

    def _feed(self, data, out):
        self.bytes_in += len(data)
        start = 0
        n = len(data)
        while start < n:
            z = data.find(b"\x00", start)
            end = n if z < 0 else z
            if not self._skipping and end > start:
                if len(self._buf) + end - start > MAX_ENCODED:
                    self.oversize += 1
                    self._skipping = True
                    self._buf = b""
                else:
                    self._buf += data[start:end]
            if z < 0:
                return
            if self._buf:
                self._segment(self._buf, out)
            self._buf = b""
            self._skipping = False
            start = z + 1

    def _segment(self, enc, out):
        body = cobs_decode(enc)
        if body is None:
            self.cobs_errors += 1
            return
        frame, why = parse_body(body)
        if frame is None:
            self._reject(body, why)
            return
        hello = None
        if frame.msg_type == HELLO:
            hello = Hello(frame)
            if hello.boot_id != self.boot_id and hello.boot_id in self.old_boots:
                self._replay(False)  # an earlier boot's HELLO played back: not a reboot
                return
            if self.boot_id is not None and hello.boot_id != self.boot_id:
                self.old_boots = (self.old_boots + [self.boot_id])[-OLD_BOOTS:]
                if not self._headless_boot:  # else the seq_jump already counted this reboot
                    self.reboots += 1
                    self._restart_seq()  # the new boot counts its sequence from its first HELLO
            self._headless_boot = False
            self._old_seen = None
        if hello is None and self._old_seen is not None and self._old_seen[frame.seq]:
            # until the new boot's HELLO, a seq the boot before it delivered cannot be told from
            # that boot's bytes played back (PROTOCOL.md, Receiver rules): dropped as a replay
            self._replay(False)
            return
        if self.last_seq is not None and not self._in_sequence(frame, hello):
            return
        if hello is not None:
            self.boot_id = hello.boot_id
            self.hello = hello
        self.last_seq = frame.seq
        self.last_t = frame.t_us
        self.replay_run = 0
        self._seen[frame.seq] = 1
        self.frames_ok += 1
        out.append(frame)

    def _in_sequence(self, frame, hello):
        # type: (Frame, Hello | None) -> bool
        """The sequence check of a frame after the first of its boot: False when it is dropped
        as a replay; else counts what its gap says (lost, a resync, a seq_jump)."""
        gap = (frame.seq - self.last_seq - 1) & SEQ_MASK
        this_boots_hello = hello is not None and hello.boot_id == self.boot_id and self._clock_tells()
        if this_boots_hello and not self._ahead(frame.t_us):
            # this boot's HELLO, not later than what was delivered: old bytes played back,
            # whichever way its seq reads (behind: never delivered when the host opened the port
            # after it; ahead: from the last seq pass), since the board stamps each HELLO afresh.
            # Taken, its fields would undo the boot's later ones, and an ahead one moved the
            # sequence check past the live frames
            self._replay(False)
            return False
        if gap >= SEQ_WINDOW and this_boots_hello:
            # this boot's HELLO, later than anything delivered: the board says where it is.
            # The host stopped reading for 32768 frames or more (a suspended laptop, Ctrl-Z)
            # while the board counted on: its seq reads as behind. At least `gap` were lost.
            self.resyncs += 1
            self.lost += gap
            self._resynced = True
        elif gap >= SEQ_WINDOW:
            if self._seen[frame.seq]:
                # delivered before in this boot: old bytes played back (or, when later in
                # time, the stall above until the board's next HELLO: counted apart)
                self._replay(self._ahead(frame.t_us))
                return False
            self.seq_jumps += 1  # never seen: a reboot whose HELLO was lost
            frame.jump = True
            if hello is None:  # (a HELLO says which boot it is: nothing to hold against it)
                self._old_seen = self._seen
            self._restart_seq()
            self._headless_boot = True  # its HELLO, when it comes, is no second reboot
        elif self._resynced and self._seen[frame.seq] and not self._ahead(frame.t_us):
            # after a resync the bytes from before the stall read as ahead in seq: their
            # time, not later than the last delivered, tells them (PROTOCOL.md)
            self._replay(False)
            return False
        else:
            self.lost += gap
        return True

    def _reject(self, body, why):
        setattr(self, why, getattr(self, why) + 1)
        if why == "malformed" and body[0] & 0x0F == HELLO:
            self.bad_hello = hello_rejection(body)

    def _replay(self, ahead):
        self.replays += 1
        self.replay_run += 1
        if ahead:
            self.replays_ahead += 1

    def _ahead(self, t_us):
        # type: (int) -> bool
        """Whether `t_us` is later than the last delivered frame's, on the device clock of
        2^ts_bits (the latest HELLO's): by less than half its period, as the host unwraps it.
        Bytes played back carry a time at or before what was delivered, unless they are older
        than half the clock's period (9 minutes at 30 bits): those cannot be told by time."""
        if self.last_t is None:
            return False
        bits = self.hello.ts_bits if self.hello is not None else 32
        delta = (t_us - self.last_t) & ((1 << bits) - 1)
        return 0 < delta < (1 << (bits - 1))

    def _clock_tells(self):
        # type: () -> bool
        """Whether t_us can order frames a whole seq cycle apart: half the device clock's
        period (how far the host unwraps it) is longer than 65536 sample periods of the announced
        rate (327 s at 200 Hz: 30 bits and more; 16 bits cannot)."""
        h = self.hello
        return h is not None and clock_reach(h.ts_bits, h.rate_hz) > SEQ_MASK + 1

    def _restart_seq(self):
        self.last_seq = None
        self._resynced = False  # seq values delivered before a resync read as ahead of it
        self._seen = bytearray(SEQ_MASK + 1)
