"""Isolator elements: the forces an isolator puts on the table, one module per kind."""
