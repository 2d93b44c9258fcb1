"""What users bring and take away: measurement and design CSV, our JSON files, and the
in-memory readings (``measurements``) they become."""
