"""Searching for missing physics: hypotheses, their order search and significance, forward selection."""
