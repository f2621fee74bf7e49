"""Files out: sRGB encoding and atomic writes, sidecars, video, buffer dumps and their
documentation, progress lines and how a signal ends a write."""
