# Boot main.py as the board would, with a host on the other end of stdin (a fake sys.stdin and
# select.poll patched into board.py): the first I2C scan finds nothing (main.py's wait for
# IMUs), then '?' arrives during the 50th sample, "x?" during the 100th, the stop word during
# the 130th. Each arrives after that sample's sensor reads, before its frame is written.
import sys

import machine

machine.I2C.empty_scans = 1
machine.I2C.reads_left = 1000000  # the stop word ends the run, not the fake bus
SCRIPT = [(100, b"?"), (200, b"x?"), (260, b"!stop!")]  # (I2C reads done, bytes then readable)


class FakeStdin:
    def __init__(self):
        self.buffer = self
        self.queue = b""
        self.script = list(SCRIPT)

    def arrived(self):
        while self.script and machine.I2C.reads >= self.script[0][0]:
            self.queue += self.script.pop(0)[1]
        return len(self.queue)

    def read(self, n):
        self.arrived()
        out, self.queue = self.queue[:n], self.queue[n:]
        return out


class FakePoll:
    def __init__(self):
        self.objs = []

    def register(self, obj, mask):
        self.objs.append((obj, mask))

    def poll(self, timeout):
        ready = []
        for obj, mask in self.objs:
            if obj is STDIN:
                if STDIN.arrived():
                    ready.append((obj, mask))
            else:
                ready.append((obj, mask))  # stdout: the host always reads
        return ready


class FakeSelect:
    POLLIN = 1
    POLLOUT = 4

    @staticmethod
    def poll():
        return FakePoll()


class FakeSys:
    platform = sys.platform
    stdout = sys.stdout


STDIN = FakeStdin()
FakeSys.stdin = STDIN

import board  # noqa: E402

board.sys = FakeSys
board.select = FakeSelect
try:
    import main  # noqa: F401
except Exception as e:
    sys.stdout.write("\r\nEXC " + repr(e) + "\r\n")
