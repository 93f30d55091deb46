"""What the figure scripts of tools/report share: headless matplotlib, CSV rows, saving a figure."""
import csv

import matplotlib

matplotlib.use("Agg")  # headless: the scripts run from phri without a display
import matplotlib.pyplot as plt  # noqa: E402,F401  (re-exported for the scripts)


def read_rows(path):
    """The rows of a CSV file with a header line, as dicts."""
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def save_figure(fig, output, dpi, title=None, title_size=None, label=None):
    """Titles `fig` (when a title is given), lays it out and writes it to `output`; prints
    "<label>: <output>" when a label is given."""
    if title is not None:
        # fontsize=None would not mean "the default title size" (figure.titlesize) to matplotlib.
        fig.suptitle(title, **({} if title_size is None else {"fontsize": title_size}))
    fig.tight_layout()
    fig.savefig(output, dpi=dpi)
    if label is not None:
        print(f"{label}: {output}")


def finish_axes(ax, xlabel, ylabel, title, log_y=False, **legend):
    """Labels, title, grid and legend of one panel."""
    if log_y:
        ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(**legend)
