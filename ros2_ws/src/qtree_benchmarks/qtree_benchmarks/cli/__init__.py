"""The code of every command of ``scripts/``: one module per script, each with ``main``."""
