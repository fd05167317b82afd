"""Scan format (placeholder for layout test)."""
