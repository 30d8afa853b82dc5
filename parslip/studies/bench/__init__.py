"""The benchmark suite behind `parslip bench`: throughput, start-up, output, exchange and memory, measured.

``stream``  the machine's memory bandwidth (a STREAM-like triad), the roofline's ceiling
``numpy_step`` a straightforward vectorised NumPy step of the same model, the baseline
``case``    one measured case, run under mpiexec; prints one JSON line
``suite``   runs the cases, prints the table and writes JSON
"""
