"""Sequential design on the real TIAGo data: K postures of another session chosen by
``design --augment --candidates-from`` versus K random ones."""
