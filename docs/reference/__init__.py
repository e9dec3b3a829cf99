"""The reference pages' tables of scene keys, commands and run outputs, printed from the code that defines them."""
