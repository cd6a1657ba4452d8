"""Offline work: recording, templates, the Interaction Graph build, evaluation, profiling, benchmarks."""
