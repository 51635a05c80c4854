"""The records database: units, equipment, runs, results and reviews (docs/records-backup.md)."""
