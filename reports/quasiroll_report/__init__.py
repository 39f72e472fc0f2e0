"""quasiroll comparison-report generator (see reports/README.md)."""
