"""weights_tools: PyTorch reference networks and HDF5 weight converters (Python side)."""
