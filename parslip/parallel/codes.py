"""The codes the compiled loop reads of the decomposition: the arrays' pad, the schedule's row kinds and task
fields, the step's phases, the re-bonding search's margin.

Apart from ``parallel.layout`` (which builds the decomposition in Python and re-exports these) so that the
compiled code depends on these few lines only: the kernel cache (``io.cache.kernel_sources``) is keyed by
the modules compiled code imports, and the layout's bookkeeping changes more often than its codes.
"""
import numpy as np

PAD = 1                 # ghost rows and columns around each block's arrays

# How much further than the re-bonding length R a free site looks for substrate sites (a): a margin
# that keeps rounding out of the search (``kernels.interface._span``).
SEARCH_MARGIN = 0.5

# Row kinds of the schedule (the compiled loop has one loop per kind).
FULL, NO_UP, NO_DOWN, MASKED = 0, 1, 2, 3
# Extra per-column forces a row adds: none, the block's interface row, the substrate's interface row.
EXTRA_NONE, EXTRA_TOP, EXTRA_BOTTOM = 0, 1, 2
# Columns of a task row: block, first row, first local column j0, node count n per row, row kind, bond mask
# (MASKED), extra force, load (1: the normal load acts), drive (1: x prescribed once the drive runs), early (a
# peer keeps these nodes), s (up/down neighbours of column c are c - 1 + s and c + s), rows (the task covers
# rows row .. row + rows - 1 over the same columns: FULL rows, or a MASKED column; row row + i has the shift
# s ^ (i & 1)), mask2 (the bond mask of the odd ones among them, i odd).
TASK_FIELDS = ("block", "row", "j0", "n", "kind", "mask", "extra", "load", "drive", "early", "s", "rows", "mask2")
# The schedule is a structured array: the compiled loop reads a task's fields by name (``task.row``).
TASK_DTYPE = np.dtype([(name, np.int64) for name in TASK_FIELDS])
# Neighbour slots (bit k of a mask): 0 right, 1 up-right, 2 up-left, 3 left, 4 down-left, 5 down-right.
ALL_BONDS = 0b111111
# The phases of a step's schedule (``layout.task_ranges``): tasks a peer needs first, then the rest.
EARLY, LATE = 0, 1
# ptr[phase, block] holds [ROWS, NODES, END]: first row task, first single-node task, end.
ROWS, NODES, END = 0, 1, 2
