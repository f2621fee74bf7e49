"""The command-line toolkit the commands share: argument parsing into a scene, size, time
and parameters (`args`), and the one-time kernel warm-up (`warmup`)."""
