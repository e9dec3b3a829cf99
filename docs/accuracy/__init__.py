"""The tables of docs/accuracy.md, printed from the accuracy studies' own results."""
