"""The station's operator web page: the server, its pages, and the run supervisor it drives."""
