"""The paper reproduced, in one place: what is specific to *On the onset of slip at adhesive elastic
interfaces* (Dawara & Viswanathan), over the generic measures of ``parslip.analysis``.

``measures`` the paper's quantities measured on any run (``parslip.open`` results); ``claims`` each of its
69 quantitative statements with a tolerance fixed beforehand, and the verdicts; ``study`` the runs the
claims need (made or reused), the claims table, the figures, and the scan of the paper's open readings;
``command`` the work of ``parslip paper`` behind its argument parsing (``cli.paper_cmds``).
"""
