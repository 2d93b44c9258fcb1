"""Studies: thin scripts that call the public API and write to results/."""
