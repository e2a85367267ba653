"""Files in and out: recordings (contract CSV), parameter sets (JSON, SSP
.ssv), time bases, and figures written as files or data URIs."""
