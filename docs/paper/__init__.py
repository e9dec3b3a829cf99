"""The tables of docs/paper.md, printed from the paper study's own results."""
