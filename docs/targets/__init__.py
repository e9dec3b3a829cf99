"""The checks and the pictures of docs/targets.md: slabs, gaps, inclined faces and the ballistic limit."""
