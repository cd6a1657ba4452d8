# Test vectors printed as hex, one per line. Run by CPython and by MicroPython (WebAssembly,
# under Node) from the same text: their outputs must be identical. Portable code only.
import protocol
from sampler import Sampler


class Ticks:
    def __init__(self, start):
        self.now = start

    def ticks_us(self):
        return self.now & 0x3FFFFFFF

    def ticks_add(self, t, d):
        return (t + d) & 0x3FFFFFFF

    def ticks_diff(self, a, b):
        return ((a - b + 0x20000000) & 0x3FFFFFFF) - 0x20000000

    def sleep_us(self, us):
        self.now += us


class IMU:
    kind = 1
    accel_lsb_per_g = 4096
    gyro_mlsb_per_dps = 65500

    def __init__(self, k):
        self.k = k
        self.n = 0

    def read(self):
        self.n += 1
        k = self.k * 1000 + self.n * 37
        return ((k * 7) % 65536 - 32768, -k % 4096, 4096 + k % 300, k % 50, -k % 60, 0)


out = []
out.append(protocol.encode_hello(0, 123456, 0xDEADBEEF, 200, 4096, 65500, 30, 1, 3))
out.append(protocol.encode_text(1, 0xFFFFFFFF, "h\u00e9llo \u2014 frames"))
out.append(protocol.encode_text(2, 5, "x" * 300))
out.append(protocol.encode_text(2, 5, "x" + "\u00e9" * 150))  # cut between characters, not inside one
out.append(protocol.encode_sample(3, 0, (0, 0, 0), (0, 0, 0)))
out.append(protocol.encode_sample(65535, 1 << 31, (-32768, 32767, 40000), None, (1, 2, 3), None, True))
out.append(protocol.encode_sample(7, 9, None, (-1, -256, 256)))
for n in (0, 1, 253, 254, 255, 300):
    out.append(protocol.cobs_encode(bytes([(i % 255) + 1 for i in range(n)])))
    out.append(protocol.cobs_encode(bytes(n)))

n = [0]


def stop(_s):
    n[0] += 1
    return n[0] > 300


wire = []


def write(b):
    wire.append(b)
    return len(b)


s = Sampler([IMU(1), IMU(2)], write, Ticks(0x3FFFFFFF - 400000), rate_hz=200, boot_id=42, ts_bits=30)
s.run(stop)
out.append(b"".join(wire))


class OtherIMU(IMU):
    kind = 2
    accel_lsb_per_g = 4098
    gyro_mlsb_per_dps = 57143


# B of another kind: its counts converted to A's scales, in integers (negative ones too)
del wire[:]
n[0] = 290
s = Sampler([IMU(3), OtherIMU(4)], write, Ticks(5), rate_hz=200, boot_id=43, ts_bits=30, gyro=True)
s.run(stop)
out.append(b"".join(wire))
for o in out:
    print(protocol.binascii.hexlify(o).decode())

d = protocol.Decoder()
frames = []
blob = b"".join(out)
for i in range(0, len(blob), 13):
    frames += d.feed(blob[i:i + 13])
print(len(frames), d.frames_ok, d.crc_errors, d.cobs_errors, d.runts, d.lost, d.seq_jumps)
print(frames[5].values())
