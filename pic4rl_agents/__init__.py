"""SB3 training and testing nodes (to be built: see the agents issue)."""
