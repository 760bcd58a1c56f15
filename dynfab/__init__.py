"""dynfab: reactive robot motion generation with (dynamic) optimization fabrics."""

__version__ = "0.1.0"
