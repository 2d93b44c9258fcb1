"""The TIAGo real data through the commands a user runs: refine on three sessions, predict
the fourth."""
