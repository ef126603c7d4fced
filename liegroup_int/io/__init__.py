"""Results on disk: streamed CSV histories, JSON summaries, plots."""

from .history import HistoryWriter, read_history
from .plots import plot_history, plot_run, plot_shapes
from .summary import write_json

__all__ = ["HistoryWriter", "read_history", "write_json", "plot_history", "plot_shapes", "plot_run"]
