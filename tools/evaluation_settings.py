"""What `quickjab evaluate`'s command line shares with the evaluation (tools/evaluate_recognition.py),
in a module that imports nothing: the parser reads its defaults here, so `quickjab recognize`,
`templates build` and every `--help` load no evaluation code (issue 14, start-up)."""

CLIP_FRAMES = 24  # the simulated character's punch clip: 0.4 s (0 = never finishes)
