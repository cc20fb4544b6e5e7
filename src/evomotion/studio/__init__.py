"""evomotion studio: a local web app over run folders (``evomotion studio``; docs/studio.md)."""
