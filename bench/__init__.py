"""PhotoDEM benchmarks: accuracy and speed side by side with peers, reported as ratios."""
