"""An independent simulator in the tool: the same primitives and policies in IR-SIM."""
