"""The numbers of README.md and docs/, one test file per page (common.py: what they share)."""
