"""The ground floor: what every package shares (input validation, output staging, provenance, statistics of
correlated samples, the HTML page shell).  It imports nothing of the project."""
