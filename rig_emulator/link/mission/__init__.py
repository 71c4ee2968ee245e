"""The mission microservice: upload and download (:mod:`.transfer`), the stored mission
(:mod:`.store`) and its execution (:mod:`.executor`)."""
