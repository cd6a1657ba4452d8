"""The CPU opponent: an Interaction Graph (Shum, Komura and Yamazaki, I3D 2008) built offline
and looked up at 60 Hz. See docs/interaction_graph.md for the state and why."""

from .runtime import DEFAULT_GRAPH, InteractionGraph, OpponentController
from .state import Situation
from .table import GraphFileError, GraphTable

__all__ = ["DEFAULT_GRAPH", "GraphFileError", "GraphTable", "InteractionGraph",
           "OpponentController", "Situation"]
