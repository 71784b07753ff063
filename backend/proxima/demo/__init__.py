"""`proxima demo`: the whole system on its embedded default (`config/demo.toml`):
simulated drones, replayed camera streams playing the demo script in a loop, the console
and the 3D view, stopped cleanly by Ctrl-C or SIGTERM. See docs/demo.md."""
