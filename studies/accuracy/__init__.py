"""What accuracy costs in time (filled in below)."""
