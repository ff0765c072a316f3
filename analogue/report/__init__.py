"""Reports: run experiments, compare with theory, write index.html + metrics.json."""
