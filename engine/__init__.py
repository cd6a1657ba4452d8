"""What any motion-controlled game needs: the fixed-step loop, budget accounting, sensor
sources, recordings and frames, the recognizer, and particle physics. Never imports `game`."""

__version__ = "0.1.0"
