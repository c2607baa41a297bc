module uavtest-pause

go 1.26.0
