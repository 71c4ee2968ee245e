"""MAVFTP (FILE_TRANSFER_PROTOCOL): every request answered with a NAK (:mod:`.nak`)."""
