"""The shared base every pic4rl package stands on: errors, geometry, the goal, files written
whole, the console scripts' runner, lazy exports and the parameter machinery (typed fields,
the params file).

It imports no other pic4rl package and loads only numpy and PyYAML, so the sim, the metrics,
the bridge and the agents may all import it (``tests/test_base.py``).
"""
