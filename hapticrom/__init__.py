"""hapticrom command-line interface and package metadata."""
