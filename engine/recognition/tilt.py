"""Tilted copies of the trained templates: the recognizer's tolerance of a grip that differs from
the training trials' (a remote held a little more upright on another day).

Each template is copied three times with each sensor's readings, gravity included, turned by
`degrees` towards three directions across that sensor's resting gravity (so a copy's activity
|a - g|, and with it every energy bar, is its source's own). The copies take their source's
action and rejection threshold. Before the first decision they count only when no other
template fits under its threshold (`TemplateSet._first_usable`): where the trained templates fit,
the resting tilt may carry the kind (phone punches: the uppercut's guard is tilted ~60 degrees
from the jab's) and a copy would blur it; switches and the final decision weigh them all
(docs/recognition.md, twenty-first round)."""

from __future__ import annotations

import numpy as np

from engine.recognition.templates import Templates

# How far a copy is turned: uWave's day 1 -> days 2-7, adaptation forgotten before each trial,
# 90.2 -> 92.0 %; 7 degrees: 91.6 %; 15: 93.2 %, but the phone punches' left slow -> fast final
# 98.5 -> 89.4 % (docs/recognition.md, twenty-first round; a new recognizer per trial gives 91.8 %
# at 10 degrees, twenty-second round).
TILT_DEG = 10.0
# The directions (radians, about the resting gravity) the copies lean to: three, 120 degrees
# apart, do what four at 90 degrees did (uWave 96.0 / 92.0 % against 96.2 / 92.3 %, phone-boxing
# type 77.9 % both) at 4/5 of the templates.
DIRECTIONS = (0.0, 2.0 * np.pi / 3.0, 4.0 * np.pi / 3.0)
NO_COPIES_FEATURES = ("grip",)  # features a turn of the sensor does not change: copies would be the same
# Copies are made for sets of at most this many templates (the game's 13 moves x 3 trials: 39 ->
# 156 with the copies): each copy is a DTW row every frame, and a set of hundreds (a player who
# recorded many trials, `quickjab bench recognition`'s 1000 x 3) holds the variety they add.
MAX_COPIED = 64


def _turns(axes: np.ndarray, angle: float) -> np.ndarray:
    """(..., 3, 3) rotations by `angle` radians about the unit vectors `axes` (..., 3) (Rodrigues);
    the identity where an axis is 0 (a sensor without gravity stays as it is)."""
    x, y, z = axes[..., 0], axes[..., 1], axes[..., 2]
    zero = np.zeros_like(x)
    k = np.stack([np.stack([zero, -z, y], -1), np.stack([z, zero, -x], -1), np.stack([-y, x, zero], -1)], -2)
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def _across(g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit axes (..., 3) across the directions of `g` (..., 3) and across each other; 0 for a
    gravity of (about) 0 g, which has no direction to turn away from."""
    size = np.linalg.norm(g, axis=-1, keepdims=True)
    u = np.where(size > 1e-6, g / np.maximum(size, 1e-300), 0.0)
    a1 = np.cross(u, np.eye(3)[np.argmin(np.abs(u), axis=-1)])
    a1 /= np.maximum(np.linalg.norm(a1, axis=-1, keepdims=True), 1e-300)
    return a1, np.cross(u, a1)


def tilted_copies(templates: Templates, degrees: float) -> tuple[Templates, np.ndarray]:
    """`templates` followed by tilted copies of each (the module docstring), and (T,) the index
    each one was turned from (its own for the given ones). `degrees` 0, or a feature a turn does
    not change, or more than MAX_COPIED templates: the templates as they are."""
    n = len(templates)
    if degrees <= 0 or templates.feature in NO_COPIES_FEATURES or n > MAX_COPIED:
        return templates, np.arange(n)
    sensors = templates.dim // 3
    a1, a2 = _across(templates.gravity.reshape(n, sensors, 3))
    # (copies, n, sensors, 3, 3): the turns, one per direction across each template's gravity
    turns = np.stack([_turns(np.cos(phi) * a1 + np.sin(phi) * a2, np.radians(degrees)) for phi in DIRECTIONS])
    actions, signals, gravity = list(templates.actions), list(templates.signals), list(templates.gravity)
    sources = list(range(n))
    for k in np.flatnonzero(a1.any(axis=(1, 2))):  # a template without any gravity has no copies
        sig = templates.signals[k].reshape(len(templates.signals[k]), sensors, 3)
        g = templates.gravity[k].reshape(sensors, 3)
        for r in turns[:, k]:
            actions.append(templates.actions[k])
            signals.append(np.einsum("sij,lsj->lsi", r, sig).reshape(len(sig), -1))
            gravity.append(np.einsum("sij,sj->si", r, g).reshape(-1))
            sources.append(int(k))
    src = np.array(sources)
    out = Templates(
        actions,
        signals,
        np.array(gravity),
        templates.onsets[src],
        templates.thresholds[src],
        templates.method,
        templates.feature,
        dict(templates.meta),
        templates.rest_noise,
        dict(templates.recognizer),
    )
    return out, src
