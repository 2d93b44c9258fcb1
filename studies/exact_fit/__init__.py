"""A model exact for any geometry of its form, on data our effect modules did not generate."""
