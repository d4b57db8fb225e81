"""What a run is, shared by every command of the agents: its three sections (``config``:
``TrainConfig``, ``RunConfig``), command-line overrides blamed on their flags (``overrides``),
a run directory's layout and the checkpoint a resume takes (``rundir``), and the commands'
console logging (``console``)."""
