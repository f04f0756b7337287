"""Camera commands judged from the recorded video: zoom by the picture's scale, palette, PiP."""
