# Boot the firmware as the board would (import main), stopping at the fake I2C's Done.
import sys

try:
    import main  # noqa: F401
except Exception as e:
    sys.stdout.write("\r\nEXC " + repr(e) + "\r\n")
