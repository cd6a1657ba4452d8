"""The serial IMU bridge: wire protocol (CPython and MicroPython), firmware, device emulator."""
