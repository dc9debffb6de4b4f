"""inflo benchmarks (``make bench``); never run by the tests."""
