-- wrk script: POST a small scene to /render?wait=1 and count status codes.
-- WRK_SCENE (path) and WRK_QUERY (query string) come from the environment.
local path = os.getenv("WRK_SCENE") or "scenes/cho.txt"
local query = os.getenv("WRK_QUERY") or "width=40&height=30&wait=1"
local f = assert(io.open(path, "rb"))
local body = f:read("*a")
f:close()

wrk.method = "POST"
wrk.body = body
wrk.headers["Content-Type"] = "text/plain"
wrk.path = "/render?" .. query

-- WRK_VARY=1: every request gets its own seed, so none is answered from the cache.
local vary = os.getenv("WRK_VARY") == "1"
local threads = {}
local counter = 0

function setup(thread)
  table.insert(threads, thread)
end

function init(args)
  codes = {}
  prefix = tostring(math.random(1, 1e9))
end

function request()
  if not vary then return wrk.format() end
  counter = counter + 1
  return wrk.format(nil, "/render?" .. query .. "&seed=" .. prefix .. counter)
end

function response(status, headers, body)
  codes[status] = (codes[status] or 0) + 1
end

function done(summary, latency, requests)
  local total = {}
  for _, t in ipairs(threads) do
    local c = t:get("codes")
    for k, v in pairs(c) do total[k] = (total[k] or 0) + v end
  end
  local parts = {}
  for k, v in pairs(total) do table.insert(parts, k .. ":" .. v) end
  table.sort(parts)
  io.write(string.format("statuses %s\n", table.concat(parts, " ")))
  io.write(string.format("latency_ms p50 %.2f p90 %.2f p99 %.2f max %.2f\n",
    latency:percentile(50) / 1000, latency:percentile(90) / 1000,
    latency:percentile(99) / 1000, latency.max / 1000))
  io.write(string.format("requests_per_second %.1f\n", summary.requests / (summary.duration / 1e6)))
end
