"""MicroPython firmware files (copied to the board as top-level modules); the host emulator imports sampler.py from here."""
