"""Jakobsen Verlet particle physics (paper section V)."""
