"""The spherical fuzzy marker-error model on joint angles (thesis §3.7, §5.5)."""
