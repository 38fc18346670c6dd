"""Sessions and logs in MCAP: the channels and their JSON schemas, the writer process, the reader, the replay
of a recorded session through a fresh simulation and its view in the browser."""
