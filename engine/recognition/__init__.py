"""Recognition: templates, the dual buffer and the incremental DTW (paper sections III-IV)."""
