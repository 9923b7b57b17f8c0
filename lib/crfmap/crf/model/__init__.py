"""What the CRF is: its potential tables (``potentials``), hard evidence (``evidence``), nav2 gating (``gating``)."""
