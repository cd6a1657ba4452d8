"""The serial source against hostile or broken links: HELLO fields that make no sense, replayed
old frames, a board that reboots with another sensor count (through `play`'s frames stage and
`record`), and hypothesis-generated streams of random and corrupted frames through loop://."""

from __future__ import annotations

import os
import random
import threading
import time
import tracemalloc
import tty

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from engine.frames import FrameResampler
from engine.recording import MAX_ACCEL_G, read_recording
from engine.sensors import open_source
from engine.sensors.serial_accel import SampleAccel
from firmware_bridge import protocol
from tools.record import link_counts, record


def hello(seq=0, boot=77, accel=4096, gyro=65500, rate=200, ts_bits=30, flags=3, t_us=0):
    return protocol.encode_hello(seq, t_us, boot, rate, accel, gyro, ts_bits, protocol.IMU_MPU6050, flags)


def samples(n, start_seq=1, t0=5000, sensors=2):
    b = (2048, -4096, 0) if sensors == 2 else None
    return b"".join(protocol.encode_sample(start_seq + i, t0 + 5000 * i, (0, 0, 4096), b) for i in range(n))


def test_hello_with_zero_or_absurd_fields_is_counted_and_dropped():
    src = open_source("serial://loop://")
    for k, bad in enumerate((hello(accel=0), hello(rate=0), hello(ts_bits=7), hello(ts_bits=33),
                             hello(gyro=0, flags=3 | protocol.FLAG_GYRO))):
        src.port.write(bad + samples(3, start_seq=1 + 4 * k))
        assert src.poll() == []  # no scales: nothing converted, nothing raised
        assert src.hello is None
    assert src.stats["malformed"] == 5 and src.stats["samples_before_hello"] == 15
    src.port.write(hello(seq=30) + samples(3, start_seq=31))
    assert len(src.poll()) == 3  # a good HELLO later: back to normal


def test_source_guards_a_bad_hello_the_decoder_let_through():
    src = open_source("serial://loop://")
    frame = protocol.Frame(protocol.HELLO, 0, 0, 3, protocol.struct.pack(protocol.HELLO_FMT, 0, 0, 200, 1, 30, 1))
    assert src._samples([frame], 0.0) == []
    assert src.stats["bad_hellos"] == 1 and src.hello is None


def test_replayed_frames_are_dropped_and_cost_no_lost_count():
    src = open_source("serial://loop://")
    first = hello() + samples(100)
    src.port.write(first)
    assert len(src.poll()) == 100
    # an attacker (or a confused adapter) plays the same bytes again, then the board goes on
    src.port.write(first + samples(10, start_seq=101, t0=5000 * 101))
    got = src.poll()
    assert len(got) == 10
    stats = src.stats
    assert stats["replays"] == 101 and stats["lost"] == 0 and stats["reboots"] == 0 and stats["seq_jumps"] == 0


def test_an_earlier_boots_hello_is_a_replay_not_a_reboot():
    src = open_source("serial://loop://")
    src.port.write(hello(boot=1) + samples(5))
    src.port.write(hello(boot=2) + samples(5))
    src.port.write(hello(boot=1) + samples(5))  # boot 1's frames played back
    assert len(src.poll()) == 10
    assert src.stats["reboots"] == 1 and src.stats["replays"] == 6


def test_real_gaps_still_count_lost_and_a_headless_reboot_is_a_jump():
    src = open_source("serial://loop://")
    src.port.write(hello() + samples(50) + samples(10, start_seq=61, t0=5000 * 61))
    assert len(src.poll()) == 60 and src.stats["lost"] == 10
    # rebooted, its HELLO lost: seq starts again low, but at seqs never seen in the old window
    src.port.write(samples(5, start_seq=40000, t0=100))
    assert len(src.poll()) == 5 and src.stats["seq_jumps"] == 1 and src.stats["lost"] == 10


def test_a_reboot_with_one_sensor_fewer_keeps_the_frames_stage_running():
    src = open_source("serial://loop://")
    res = FrameResampler(sensors=2)
    src.port.write(hello(boot=1) + samples(40))
    got = src.poll()
    res.push(got)
    f = res.frame_at(got[-1].t).copy()
    np.testing.assert_allclose(f, [0, 0, 1, 0.5, -1, 0])
    # the board rebooted and found only sensor A: HELLO with one sensor, then 1-sensor SAMPLEs
    src.port.write(hello(boot=2, flags=protocol.FLAG_SENSOR_A) + samples(40, sensors=1, t0=300_000))
    got2 = src.poll()
    assert len(got2) == 40 and got2[0].accel.shape == (1, 3)
    assert src.sensors == 1 and src.stats["sensor_changes"] == 1
    res.push(got2)
    for s in got2:
        f = res.frame_at(s.t)  # raised a broadcast error before
        np.testing.assert_allclose(f, [0, 0, 1, 0.5, -1, 0])  # sensor B holds its last value
    assert res.resized == 40


def record_while(board, out) -> int:
    """`quickjab record` for 1 s from a raw pty's slave end while `board(master)` writes its
    master end in a thread; both ends closed after. The rows recorded."""
    master, slave = os.openpty()
    tty.setraw(slave)
    th = threading.Thread(target=board, args=(master,))
    th.start()
    try:
        return record(f"serial://{os.ttyname(slave)}", str(out), 1.0)
    finally:
        th.join()
        os.close(master)
        os.close(slave)


def test_record_continues_in_a_new_file_when_the_sensor_count_changes(tmp_path, capsys):
    out = tmp_path / "rec.csv"

    def board(master: int) -> None:
        time.sleep(0.2)
        os.write(master, hello(boot=1) + samples(30))
        time.sleep(0.2)
        os.write(master, b"\x00\x05\x01garbage" + samples(3, start_seq=40, t0=5000 * 40))  # 9 lost
        time.sleep(0.2)
        os.write(master, hello(boot=2, flags=protocol.FLAG_SENSOR_A) + samples(20, sensors=1, t0=9_000_000))

    rows = record_while(board, out)
    assert rows == 53
    a, b = read_recording(out), read_recording(tmp_path / "rec.2.csv")  # both read back
    assert (a.sensors, len(a), b.sensors, len(b)) == (2, 33, 1, 20)
    assert b.meta["continues"] == "rec.csv" and b.t[0] > a.t[-1]
    err = capsys.readouterr().err
    assert "now 1 sensor(s), continuing in a new file" in err
    link = next(line for line in err.splitlines() if line.startswith("link:"))
    assert "received 55 frames, lost 9, CRC-rejected 0" in link and "reboots 1" in link and "other rejects 1" in link


def test_the_link_line_says_which_reboots_came_without_a_hello():
    both = link_counts({"frames_ok": 10, "reboots": 1, "seq_jumps": 2})
    assert "reboots 3 (2 seen only as a sequence jump)," in both
    announced = link_counts({"frames_ok": 10, "reboots": 1})
    assert "reboots 1," in announced and "sequence jump" not in announced


# -- fuzz ---------------------------------------------------------------------------------

def _frame(draw_kind: int, rng: random.Random, seqs: list[int]) -> bytes:
    nxt = seqs[-1] + 1 if seqs else 0
    seq = rng.choice([rng.randrange(65536), nxt, nxt, nxt, rng.choice(seqs) if seqs else 0])
    seqs.append(seq & 0xFFFF)
    t = rng.randrange(1 << 32)
    if draw_kind == 0:
        if rng.random() < 0.7:  # a plausible HELLO (any scale, rate, sensor set, clock width)
            return protocol.encode_hello(seq, t, rng.choice([1, 2, 3]), rng.randrange(1, 2000), rng.randrange(1, 65536),
                                         rng.randrange(1, 1 << 32), rng.randrange(8, 33), rng.randrange(4),
                                         rng.randrange(8))
        return protocol.encode_hello(seq, t, rng.choice([1, 2, rng.randrange(1 << 32)]), rng.randrange(65536),
                                     rng.randrange(65536), rng.randrange(1 << 32), rng.randrange(256),
                                     rng.randrange(256), rng.randrange(16))
    if draw_kind == 1:
        gyro = rng.random() < 0.2
        a = tuple(rng.randrange(-32768, 32768) for _ in range(3))
        b = tuple(rng.randrange(-32768, 32768) for _ in range(3)) if rng.random() < 0.7 else None
        if b is None and rng.random() < 0.3:
            a, b = None, a
        g = (1, 2, 3) if gyro else None
        return protocol.encode_sample(seq, t, a, b, g if a else None, g if b else None, rng.random() < 0.1)
    if draw_kind == 2:
        return protocol.encode_text(seq, t, rng.randbytes(rng.randrange(0, 250)))
    # a CRC-valid body with any layout: wrong lengths, unknown flags and types
    body = bytes([rng.randrange(256)]) + rng.randbytes(rng.randrange(0, 40))
    kind = body[0] & 0x0F
    extra = protocol.CRC_EXTRA.get(kind, 0)
    crc = protocol.binascii.crc32(bytes((extra,)), protocol.binascii.crc32(body)) & 0xFFFFFFFF
    return b"\x00" + protocol.cobs_encode(body + protocol.struct.pack("<I", crc)) + b"\x00"


def _damage(data: bytes, how: int, rng: random.Random) -> bytes:
    if not data or how == 0 or how > 4:  # (how 5.. : undamaged)
        return data
    b = bytearray(data)
    i = rng.randrange(len(b))
    if how == 1:
        b[i] ^= 1 << rng.randrange(8)
    elif how == 2:
        del b[i]
    elif how == 3:
        del b[i:]
    else:
        b[i:i] = rng.randbytes(rng.randrange(1, 600))
    return bytes(b)


FUZZ = {"streams": 0, "frames": 0, "samples": 0}


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.sampled_from([0, 1, 1, 1, 1, 2, 3, 4]), st.integers(0, 9)), min_size=1, max_size=120),
       st.integers(0, 2**32 - 1))
def test_fuzzed_streams_give_valid_samples_or_nothing(plan, seed):
    """Random, CRC-valid-but-absurd and damaged frames, replays included: every poll returns in
    bounded time, never raises, and every sample is finite, (sensors, 3) and in time order."""
    rng = random.Random(seed)
    src = open_source("serial://loop://")
    seqs: list[int] = []
    chunks = []
    for kind, how in plan:
        frame = _frame(kind, rng, seqs) if kind < 4 else rng.choice(chunks) if chunks else b"\x00"
        chunks.append(_damage(frame, how, rng))
    data = b"".join(chunks)
    last_t = -np.inf
    got = 0
    start = time.perf_counter()
    for i in range(0, len(data), 1000):  # loop:// in bites, as a port would deliver them
        src.port.write(data[i : i + 1000])
        for s in src.poll():
            a = np.asarray(s.accel)
            # (a poll may hold samples from before and after a HELLO that changed the sensor count)
            assert a.ndim == 2 and a.shape[1] == 3 and a.shape[0] in (1, 2)
            assert np.all(np.isfinite(a)) and np.all(np.abs(a) <= MAX_ACCEL_G)  # HELLOs may scale by 1
            assert s.t >= last_t and np.isfinite(s.t)
            last_t = s.t
            got += 1
    assert time.perf_counter() - start < 5.0  # no hang
    assert len(src.decoder._buf) <= protocol.MAX_ENCODED and len(src.messages) <= 32
    FUZZ["streams"] += 1
    FUZZ["frames"] += len(plan)
    FUZZ["samples"] += got
    src.close()


def test_fuzz_memory_stays_flat():
    """A long hostile stream through one source on a real pty: memory after 10000 more frames is
    what it was after 1000 (no per-frame growth: seen-seq window, message queue, decoder buffer
    all bounded)."""
    rng = random.Random(5)
    master, slave = os.openpty()
    tty.setraw(slave)
    src = open_source(f"serial://{os.ttyname(slave)}")
    seqs: list[int] = []
    counts = {"frames": 0, "samples": 0}

    def feed(n):
        for _ in range(n):
            os.write(master, _damage(_frame(rng.randrange(4), rng, seqs), rng.randrange(10), rng))
            counts["samples"] += len(src.poll())
            counts["frames"] += 1
            del seqs[:-100]

    try:
        feed(1000)
        tracemalloc.start()
        feed(1000)
        base = tracemalloc.get_traced_memory()[0]
        feed(10000)
        grown = tracemalloc.get_traced_memory()[0] - base
        tracemalloc.stop()
    finally:
        src.close()
        os.close(master)
        os.close(slave)
    print(f"fuzz: hypothesis {FUZZ}; one pty stream {counts}, {src.stats}; "
          f"memory growth over the last 10000 frames: {grown} B")
    assert counts["samples"] > 500  # the stream was not all garbage
    assert grown < 200_000


def test_a_reboot_whose_hello_was_lost_counts_once():
    src = open_source("serial://loop://")
    # the host came in mid-stream (seq 30000 on), then the board rebooted and its HELLO was lost:
    # seq 1.. again, behind but never seen, then the new boot's next HELLO
    data = (hello(boot=1, seq=29999) + samples(600, start_seq=30000)
            + samples(200, start_seq=1, t0=100) + hello(boot=2, seq=201, t_us=1_000_100)
            + samples(5, start_seq=202, t0=1_005_100))
    got = 0
    for i in range(0, len(data), 2000):  # loop:// holds 4096 bytes: a bigger write would block
        src.port.write(data[i : i + 2000])
        got += len(src.poll())
    assert got == 805
    stats = src.stats
    assert stats["seq_jumps"] == 1 and stats["reboots"] == 0 and stats["lost"] == 0


# -- the device clock restarting inside one read, on a real port ----------------------------

UP_US = 600_000_000  # the board has been up 600 s: its clock is far from a fresh boot's


def _pty_source():
    master, slave = os.openpty()
    tty.setraw(slave)
    return master, slave, open_source(f"serial://{os.ttyname(slave)}")


def _write_and_poll(data: bytes, done) -> tuple[object, list]:
    """A pty serial source fed `data` in one write, polled until `done(src)` (at most 1 s); the
    source (closed) and the samples it gave."""
    master, slave, src = _pty_source()
    got: list = []
    try:
        os.write(master, data)
        for _ in range(100):
            got += src.poll()
            if done(src):
                break
            time.sleep(0.01)
    finally:
        src.close()
        os.close(master)
        os.close(slave)
    return src, got


def _poll_all(src, want: int) -> list[tuple[float, float]]:
    """(sample t, host time right after the poll that returned it) until `want` samples came."""
    got: list[tuple[float, float]] = []
    for _ in range(100):
        samples = src.poll()
        now = time.perf_counter()
        got += [(s.t, now) for s in samples]
        if len(got) >= want:
            break
        time.sleep(0.005)
    assert len(got) == want
    return got


def _clock_restart_run(batch: bytes, batch_samples: int, next_seq: int, next_t0: int) -> list[tuple[float, float]]:
    """A board streams for 0.2 s, then one write holds `batch` (in which its clock restarts),
    then it streams on from `next_seq` / `next_t0` for 0.3 s; every sample with its poll's time."""
    master, slave, src = _pty_source()
    got = []
    try:
        os.write(master, hello(seq=999, boot=7, ts_bits=32, t_us=UP_US))
        seq = 1000
        for _ in range(10):  # steady streaming at 200 Hz, a read every 20 ms
            os.write(master, samples(4, start_seq=seq, t0=UP_US + 5000 * seq))
            seq += 4
            time.sleep(0.02)
            got += _poll_all(src, 4)
        time.sleep(0.02)
        os.write(master, batch)
        time.sleep(0.02)
        got += _poll_all(src, batch_samples)
        for k in range(10):
            os.write(master, samples(6, start_seq=next_seq + 6 * k, t0=next_t0 + 30_000 * k))
            time.sleep(0.03)
            got += _poll_all(src, 6)
    finally:
        src.close()
        os.close(master)
        os.close(slave)
    t = np.array([s for s, _ in got])
    assert np.all(np.diff(t) >= 0)
    late = [round(s - now, 3) for s, now in got if s > now]
    assert late == []  # PROTOCOL.md, host time: never later than the poll that saw the sample
    after = t[-60:]  # the last 0.3 s of streaming: spread over it, not frozen at one time
    assert after[-1] - after[0] > 0.15
    return got


def test_a_reboot_whose_hello_is_lost_inside_one_read_keeps_host_time():
    # the old boot's last two samples and the new boot's first three (seq 0, its clock at 1 ms,
    # its HELLO lost) arrive in one read: the old ones keep the old boot's clock offset
    seq = 1040
    batch = samples(2, start_seq=seq, t0=UP_US + 5000 * seq) + samples(3, start_seq=0, t0=1000)
    _clock_restart_run(batch, 5, next_seq=3, next_t0=1000 + 3 * 5000)


def test_one_sample_with_a_wild_timestamp_inside_one_read_keeps_host_time():
    # one CRC-valid SAMPLE whose t_us is 2000 s ahead, then the stream as it was
    seq = 1040
    t0 = UP_US + 5000 * seq
    batch = (protocol.encode_sample(seq, t0 + 2_000_000_000, (0, 0, 4096), (2048, -4096, 0))
             + samples(2, start_seq=seq + 1, t0=t0 + 5000))
    _clock_restart_run(batch, 3, next_seq=seq + 3, next_t0=t0 + 15_000)


def test_a_hello_that_changes_sensors_within_one_boot_is_dropped_and_record_keeps_one_file(tmp_path, capsys):
    # a broken board whose HELLOs alternate sensor A and A|B under one boot_id: a boot's
    # sensors are fixed once announced, so each flipped HELLO is counted and dropped, its
    # one-sensor SAMPLEs hold B's last value, and the recording stays in one file
    out = tmp_path / "rec.csv"

    def board(master: int) -> None:
        time.sleep(0.2)
        seq = 0
        for k in range(10):
            flags = protocol.FLAG_SENSOR_A if k % 2 else 3
            os.write(master, hello(seq=seq, boot=7, flags=flags, t_us=5000 * seq)
                     + samples(10, start_seq=seq + 1, t0=5000 * (seq + 1), sensors=1 if k % 2 else 2))
            seq += 11
            time.sleep(0.05)

    rows = record_while(board, out)
    assert rows == 100
    rec = read_recording(out)
    assert rec.sensors == 2 and len(rec) == 100
    assert not (tmp_path / "rec.2.csv").exists()
    err = capsys.readouterr().err
    assert "continuing in a new file" not in err
    link = next(line for line in err.splitlines() if line.startswith("link:"))
    assert "sensor changes 0" in link and "sensor conflicts 5" in link


def test_a_text_frame_with_flags_set_is_malformed():
    # PROTOCOL.md: "TEXT frames carry flags 0"; the firmware's encode_text sends 0
    data = b"".join(protocol.encode_frame(protocol.TEXT, seq, 5000 * seq, flags, b"flags %d" % flags)
                    for seq, flags in ((1, 0x0F), (2, protocol.FLAG_SENSOR_A), (3, 0)))
    src, _ = _write_and_poll(data, lambda src: src.stats["frames_ok"] + src.stats["malformed"] == 3)
    assert list(src.messages) == ["flags 0"]
    assert src.stats["malformed"] == 2 and src.stats["frames_ok"] == 1 and src.stats["texts"] == 1


# -- readings no sensor gives: a HELLO with a tiny accel scale ------------------------------

def _tiny_scale_stream(seq0: int = 0, t0: int = 0) -> tuple[bytes, list]:
    """A HELLO with accel_lsb_per_g 1 (valid: 1..65535) and gyro, then SAMPLEs whose counts are
    g as they are: the in-range ones (and what each should read as, in g) and the out-of-range.
    Gyro counts are at full scale in every frame: they are not accelerations."""
    gyro = (32767, -32768, 1)
    frames = [  # (accel A, accel B, plausible)
        ((0, 0, 1), (1, 0, 0), True),
        ((1000, -1000, 0), (0, 0, -1000), True),  # exactly the limit reads back
        ((0, 0, 1001), (0, 0, 1), False),
        ((0, 0, 1), (-32768, 0, 0), False),  # one axis of the second sensor is enough
        ((32767, 32767, 32767), (32767, 32767, 32767), False),
        ((2, 3, 4), None, True),  # B missing: holds its last *plausible* value, (0, 0, -1000)
    ]
    data = hello(seq=seq0, accel=1, flags=3 | protocol.FLAG_GYRO, t_us=t0)
    want = []
    for k, (a, b, ok) in enumerate(frames):
        seq = seq0 + 1 + k
        data += protocol.encode_sample(seq, t0 + 5000 * (k + 1), a, b, gyro, gyro if b else None)
        if ok:
            want.append([list(a), list(b or (0, 0, -1000))])
    return data, want


def test_samples_over_the_acceleration_limit_are_dropped_and_counted():
    # PROTOCOL.md allows any accel_lsb_per_g from 1: at 1 count per g an int16 reads up to
    # 32,767 g, which the recording reader (MAX_ACCEL_G) refuses and no worn sensor gives
    data, want = _tiny_scale_stream()
    src, got = _write_and_poll(data, lambda src: src.stats["frames_ok"] == 7)
    assert src.hello is not None and src.hello.accel_lsb_per_g == 1
    assert [s.accel.tolist() for s in got] == want
    assert all(np.abs(s.accel).max() <= MAX_ACCEL_G for s in got)
    assert src.stats["implausible"] == 3 and src.stats["malformed"] == 0 and src.stats["sensor_missing"] == 1


def test_record_of_a_tiny_scale_stream_reads_back(tmp_path, capsys):
    out = tmp_path / "rec.csv"

    def board(master: int) -> None:
        time.sleep(0.2)
        for k in range(5):  # five rounds of the stream, the HELLO repeated as a board does
            data, _ = _tiny_scale_stream(seq0=7 * k, t0=35_000 * k)
            os.write(master, data)
            time.sleep(0.05)

    rows = record_while(board, out)
    rec = read_recording(out)  # refused before: "an acceleration of 1001 g, over the 1000 g ..."
    assert rows == len(rec) == 15 and np.abs(rec.accel).max() == MAX_ACCEL_G
    np.testing.assert_allclose(rec.accel[:3], [[[0, 0, 1], [1, 0, 0]], [[1000, -1000, 0], [0, 0, -1000]],
                                               [[2, 3, 4], [0, 0, -1000]]])
    link = next(line for line in capsys.readouterr().err.splitlines() if line.startswith("link:"))
    assert "implausible 15" in link


def test_the_acceleration_limit_in_counts_at_the_scales_around_it():
    # at 33 counts per g an int16 stays under 1000 g (32768 / 33 = 993 g); at 32 it can pass it
    def frame(a):
        return protocol.Frame(protocol.SAMPLE, 1, 0, protocol.FLAG_SENSOR_A,
                              protocol.struct.pack("<3h", *a))

    def scale(lsb):
        return protocol.Hello(protocol.Frame(protocol.HELLO, 0, 0, protocol.FLAG_SENSOR_A,
                                             protocol.struct.pack(protocol.HELLO_FMT, lsb, 65500, 200, 1, 30, 1)))

    assert SampleAccel.plausible(frame((-32768, 32767, 0)), scale(33))
    assert SampleAccel.plausible(frame((-32000, 32000, 0)), scale(32))
    assert not SampleAccel.plausible(frame((0, 0, -32001)), scale(32))


def test_a_boot_that_finds_its_imu_late_counts_no_sensor_change():
    # the firmware's wait for IMUs (main.py): HELLOs with no sensor flags, and a TEXT, until
    # detection finds them, then HELLOs with the sensors found. A boot's first sensors are no
    # change (PROTOCOL.md, HELLO); a one-IMU board counted one, since the source starts at 2
    data = (hello(seq=0, boot=5, flags=0) + protocol.encode_text(1, 10, "no IMU found; I2C scan: ")
            + hello(seq=2, boot=5, flags=protocol.FLAG_SENSOR_A, t_us=1_000_000)
            + samples(3, start_seq=3, t0=1_005_000, sensors=1)
            # rebooted, and found both this time: that is a change, counted once
            + hello(seq=0, boot=6, flags=0, t_us=100) + hello(seq=1, boot=6, flags=3, t_us=1_000_100)
            + samples(3, start_seq=2, t0=1_005_100))
    src, got = _write_and_poll(data, lambda src: src.stats["frames_ok"] == 11)
    assert [s.accel.shape for s in got] == [(1, 3)] * 3 + [(2, 3)] * 3
    assert src.sensors == 2 and src.stats["reboots"] == 1
    assert src.stats.get("sensor_changes", 0) == 1 and src.stats.get("sensor_conflicts", 0) == 0


def test_a_long_text_is_cut_on_a_character_boundary():
    # PROTOCOL.md: a TEXT payload is 0..200 bytes of UTF-8. encode_text cut a longer line at byte
    # 200 even inside a character, so the host showed a replacement character for its last half
    line = "capteurs " + "é" * 150  # 309 bytes of UTF-8; byte 200 is the first of an é
    src, _ = _write_and_poll(protocol.encode_text(1, 5000, line), lambda src: src.stats["frames_ok"] == 1)
    (got,) = src.messages
    assert "\ufffd" not in got and line.startswith(got)
    assert len(got.encode()) == protocol.MAX_TEXT - 1  # as much as fits: 9 + 95 * 2 bytes


def test_a_hello_whose_clock_wraps_within_a_sample_period_is_taken_and_counted():
    # ts_bits 12 at 200 Hz: t_us wraps every 4.1 ms, each frame 5 ms after the last, so the host
    # cannot unwrap it (each step reads 0.9 ms). PROTOCOL.md allows ts_bits 8..32: the HELLO is
    # taken and its samples delivered, and the host counts `narrow_clock` once for it
    def stream(ts_bits: int) -> bytes:
        mask = (1 << ts_bits) - 1
        return hello(ts_bits=ts_bits) + b"".join(
            protocol.encode_sample(k, (5000 * k) & mask, (0, 0, 4096), (2048, -4096, 0)) for k in range(1, 21))

    src, got = _write_and_poll(stream(12), lambda src: src.stats["frames_ok"] == 21)
    assert len(got) == 20 and src.hello is not None and src.hello.ts_bits == 12
    assert src.stats["narrow_clock"] == 1 and src.stats.get("malformed", 0) == 0
    src, got = _write_and_poll(stream(14), lambda src: src.stats["frames_ok"] == 21)  # wraps every 16.4 ms
    assert len(got) == 20 and src.stats.get("narrow_clock", 0) == 0 and src.stats.get("malformed", 0) == 0
    np.testing.assert_allclose(np.diff([s.t for s in got]), 0.005, atol=1e-9)


def test_a_sample_with_a_sensor_its_hello_did_not_announce_is_counted_as_such():
    # HELLO: sensor A only. A SAMPLE that also carries B has nothing missing, yet was counted
    # as `sensor_missing`; B's values are dropped (the samples keep the HELLO's one row)
    a_only = hello(flags=protocol.FLAG_SENSOR_A)
    data = (a_only + samples(2, sensors=2) + samples(1, start_seq=3, t0=15000, sensors=1)
            + protocol.encode_sample(4, 20000, None, (0, 4096, 0)))  # B alone: A missing, B extra
    src, got = _write_and_poll(data, lambda src: src.stats["frames_ok"] == 5)
    assert [s.accel.tolist() for s in got] == [[[0, 0, 1]]] * 4  # A as read, then held
    assert src.stats["sensor_unannounced"] == 3 and src.stats["sensor_missing"] == 1


def test_a_text_that_is_not_utf8_is_kept_with_replacement_characters():
    # PROTOCOL.md: a TEXT is a log line; bytes that are not UTF-8 show as U+FFFD, the line is kept
    data = protocol.encode_frame(protocol.TEXT, 1, 5000, 0, b"sensor \xff\xfe B")
    src, _ = _write_and_poll(data, lambda src: src.stats["frames_ok"] == 1)
    assert list(src.messages) == ["sensor \ufffd\ufffd B"] and src.stats["malformed"] == 0


def _requests_after(data: bytes, first_seq: int = 0) -> bytes:
    """What the host writes to a pty board once it has taken a boot's HELLO (at `first_seq`) and
    100 samples and 0.3 s have passed (the request at open drained), then read `data` and polled."""
    master, slave, src = _pty_source()
    try:
        os.write(master, hello(boot=1, seq=first_seq, t_us=5000 * first_seq) + samples(100, start_seq=first_seq + 1,
                                                                                     t0=5000 * (first_seq + 1)))
        for _ in range(100):
            if len(src.poll()) or src.stats.get("frames_ok", 0) >= 101:
                break
            time.sleep(0.01)
        time.sleep(0.3)  # past the 0.25 s between two requests
        os.set_blocking(master, False)
        try:
            os.read(master, 100)  # the request sent at open
        except BlockingIOError:
            pass
        os.write(master, data)
        for _ in range(50):
            src.poll()
            time.sleep(0.01)
        try:
            return os.read(master, 100)
        except BlockingIOError:
            return b""
    finally:
        src.close()
        os.close(master)
        os.close(slave)


def test_a_reboot_whose_hello_was_lost_asks_for_the_new_boots_hello():
    # The board rebooted and its boot HELLO was lost: the new boot's seqs 1.. were all delivered by
    # the old boot, so its frames are dropped as replays until its next HELLO, up to a second.
    # The host asks for that HELLO at once (`?`), as it does while SAMPLEs come before any HELLO
    assert _requests_after(samples(20, t0=50)) == protocol.HELLO_REQUEST
    # a board streaming on, no replay and no jump: nothing asked
    assert _requests_after(samples(20, start_seq=101, t0=5000 * 101)) == b""


def test_a_reboot_after_seq_32767_whose_hello_was_lost_asks_for_it_too():
    # The old boot's seq was past half the counter: the new boot's 1, 2, ... read as a forward gap
    # (thousands lost), not a jump, and its samples were converted with the old boot's scales
    # for up to a second. Its device clock went back: that asks for the HELLO as a jump does.
    assert _requests_after(samples(20, start_seq=1, t0=50), first_seq=50_000) == protocol.HELLO_REQUEST
    assert _requests_after(samples(20, start_seq=50_101, t0=5000 * 50_101), first_seq=50_000) == b""


def test_after_a_headless_reboot_the_old_boots_bytes_are_replays_until_its_hello():
    # PROTOCOL.md, Receiver rules: until the new boot's HELLO, its frames at seq values the old
    # boot delivered are dropped as replays. The record of those values was wiped at the jump, so
    # the old boot's seq-150 bytes played back came through as a sample (a stale 1 g reading)
    # and counted 148 lost.
    src = open_source("serial://loop://")
    src.port.write(hello(seq=98) + samples(102, start_seq=99))  # the old boot delivers 98-200
    assert len(src.poll()) == 102
    src.port.write(samples(1, start_seq=1, t0=10_000))  # rebooted, its HELLO lost: seq 1
    src.port.write(samples(1, start_seq=150, t0=5000 * 52))  # the old boot's bytes again
    got = src.poll()
    assert len(got) == 1 and src.stats["seq_jumps"] == 1 and src.stats["replays"] == 1 and src.stats["lost"] == 0
    src.port.write(hello(seq=2, boot=78, t_us=15_000) + samples(3, start_seq=3, t0=20_000))  # its HELLO
    assert len(src.poll()) == 3
    assert src.stats["reboots"] == 0 and src.stats["lost"] == 0  # the jump counted that reboot


def test_a_seq_delivered_on_an_earlier_pass_of_the_counter_is_a_replay():
    # "whose seq this boot already delivered": a seq lost on this pass of the 16-bit counter was
    # still delivered on the last one, so its bytes played back are a replay, not a reboot
    dec = protocol.Decoder()
    dec.feed(hello(seq=0) + b"".join(protocol.encode_sample(s & protocol.SEQ_MASK, 5000 * s, (0, 0, 4096), None)
                                   for s in range(1, 65536 + 50)))
    dec.feed(protocol.encode_sample(60, 5000 * (65536 + 60), (0, 0, 4096), None))  # 50-59 lost on pass 2
    old = protocol.encode_sample(55, 5000 * 55, (0, 0, 4096), None)  # pass 1's seq 55, played back
    assert dec.feed(old) == []
    assert (dec.replays, dec.seq_jumps, dec.lost) == (1, 0, 10)


def test_a_hello_that_announced_no_sensor_drops_the_samples_it_has_no_place_for():
    # PROTOCOL.md: a sensor the HELLO did not announce is ignored (sensor_unannounced). After the
    # HELLO a board sends before it has found an IMU (flags 0), the values were taken as they came,
    # sensor B's reading landing in sensor A's place.
    src = open_source("serial://loop://")
    b_only = protocol.encode_sample(1, 5000, None, (0, 0, -4096))
    src.port.write(hello(flags=0) + b_only)
    assert src.poll() == [] and src.stats["sensor_unannounced"] == 1
    src.port.write(hello(seq=2, flags=protocol.FLAG_SENSOR_B, t_us=10_000)
                   + protocol.encode_sample(3, 15_000, None, (0, 0, -4096)))
    got = src.poll()
    # sensor B is the left hand (PROTOCOL.md): its row is the second, the right hand's holds still
    assert len(got) == 1 and got[0].accel.tolist() == [[0.0, 0.0, 0.0], [0.0, 0.0, -1.0]]


def test_mapped_times_are_never_later_than_the_poll():
    # dev + (now - dev) can round one step past `now` (here with t_us near the 2**32 wrap)
    src = open_source("serial://loop://", clock=lambda: 1000.05)
    base = (1 << 32) - 10_000
    src.port.write(hello(ts_bits=32, flags=1, t_us=base - 5000)
                   + b"".join(protocol.encode_sample(1 + i, (base + 5000 * i) & 0xFFFFFFFF, (0, 0, 4096), None)
                              for i in range(5)))
    got = src.poll()
    assert len(got) == 5 and max(s.t for s in got) <= 1000.05


def test_a_reboot_from_both_sensors_to_b_alone_holds_no_old_reading_and_counts_a_change():
    # sensor B alone keeps two rows (the right hand's row holding still), so the width did not
    # change: the right hand kept the old boot's last reading for good, and no change was counted
    right = protocol.encode_sample(41, 5000 * 41, (8000, 0, 4096), (0, 0, 4096))  # 1.95 g on the right
    b_only = b"".join(protocol.encode_sample(1 + i, 5000 * (1 + i), None, (2048, 0, 4096)) for i in range(20))
    data = hello(boot=1) + samples(40) + right + hello(boot=2, flags=protocol.FLAG_SENSOR_B) + b_only
    src, got = _write_and_poll(data, lambda s: s.stats.get("frames_ok", 0) >= 63)
    assert len(got) == 61 and src.stats["reboots"] == 1
    np.testing.assert_allclose(got[40].accel[0], [8000 / 4096, 0, 1])
    for s in got[41:]:  # the new boot's: no right-hand sensor, which reads 0 g (PROTOCOL.md, README)
        np.testing.assert_allclose(s.accel, [[0, 0, 0], [0.5, 0, 1]])
    assert src.sensors == 2 and src.stats["sensor_changes"] == 1
