-- Argo CD health check of uavtest.io UavTest and UavTestRun objects (Lua 5.1, as Argo CD's
-- gopher-lua runs it). It reads the kstatus conditions the operator writes (the ones Flux reads):
--   Stalled True (the newest run failed, or ended in bench errors)  -> Degraded
--   spec not picked up yet (observedGeneration behind generation)    -> Progressing
--   Reconciling True (a run is flying or being aggregated)           -> Progressing
--   Ready True (the newest run passed)                               -> Healthy
-- Install: charts/uavtest/files/argocd/README.md.
local hs = { status = "Progressing", message = "waiting for the uavtest operator" }
if obj.status == nil then
  return hs
end
local generation = obj.metadata and obj.metadata.generation
local observed = obj.status.observedGeneration
if generation ~= nil and (observed == nil or observed < generation) then
  hs.message = "the operator has not started a run of generation " .. tostring(generation) .. " yet"
  return hs
end
local conditions = {}
if obj.status.conditions ~= nil then
  for _, c in ipairs(obj.status.conditions) do
    conditions[c.type] = c
  end
end
local function holds(t)
  return conditions[t] ~= nil and conditions[t].status == "True"
end
local function says(t)
  return conditions[t].message or conditions[t].reason or t
end
if holds("Stalled") then
  hs.status = "Degraded"
  hs.message = says("Stalled")
elseif holds("Reconciling") then
  hs.status = "Progressing"
  hs.message = says("Reconciling")
elseif holds("Ready") then
  hs.status = "Healthy"
  hs.message = says("Ready")
end
return hs
