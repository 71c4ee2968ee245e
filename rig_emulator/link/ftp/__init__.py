"""MAVFTP (FILE_TRANSFER_PROTOCOL): the file server (:mod:`.server`) and the component metadata
it serves (:mod:`.component_metadata`)."""
