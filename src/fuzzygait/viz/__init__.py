"""Figures, reports and recordings: matplotlib figures of joint angles, fuzzy bands,
simulations and FRV studies; the clinicians' HTML report (:mod:`fuzzygait.viz.report`);
Rerun recordings (:mod:`fuzzygait.viz.rerun_log`); terminal summaries
(:mod:`fuzzygait.viz.summary`)."""
