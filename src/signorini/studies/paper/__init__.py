"""The paper's study: Tables 1–2 (``tables``), Figures 2–3 (``figures``, data of Figure 2 from
``sample``), the reproduction report (``reproduction``, against ``reference``) and the run
times (``runtime``), rendered from the scene named by ``figures_scene``."""
