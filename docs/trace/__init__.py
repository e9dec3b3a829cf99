"""The module every Python process of a traced docs command loads first, to list the files it reads."""
