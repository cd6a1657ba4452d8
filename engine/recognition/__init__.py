"""Recognition: templates, the dual buffer and the incremental DTW (paper sections III-IV).

    from engine.recognition import Templates, DualBufferRecognizer
    templates = Templates.from_trials({"hook_r": [trial, ...]})  # (n, D) at 60 Hz in g
    rec = DualBufferRecognizer(templates)
    rec = DualBufferRecognizer.from_config(templates, RecognizerConfig(noise_g=0.5))  # settings as data
    events = rec.push(frame)                                      # list of RecognizerEvent (.to_dict(): docs/formats.md)
"""

from engine.recognition.config import RecognizerConfig
from engine.recognition.dual_buffer import DualBufferRecognizer
from engine.recognition.events import RecognizerEvent
from engine.recognition.templates import TemplateFileError, Templates

__all__ = ["DualBufferRecognizer", "RecognizerConfig", "RecognizerEvent", "Templates", "TemplateFileError"]
