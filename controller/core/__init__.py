"""The framework of the real-time chain: the layer shape, the chain order, the loop, the data types, and
the system that builds the chain."""
