"""Configuration, result files and reports (everything that touches the disk)."""
