"""The TIAGo real data compensated: a model identified on three sessions moves the fourth's
postures; the change is predicted (nobody ran the compensated postures)."""
