"""The scripts behind the pages' generated blocks, each run as ``python -m docs.NAME`` from the repository root."""
