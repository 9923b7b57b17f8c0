"""What the CRF is: its potential tables (``potentials``), hard evidence (``evidence``)."""
