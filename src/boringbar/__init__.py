"""boringbar: vibration and chatter of impact-damped boring bars.

Public names only; the modules behind them are the layers described in
docs/architecture.md.
"""

__version__ = "0.1.0"
