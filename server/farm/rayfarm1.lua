#!lua name=rayfarm1
-- The farm's job-state machine, run inside Redis 7.0 as one Function library so that every
-- transition is atomic and takes one round trip. Built into rayfarmd (farm_library.cmake) and
-- loaded with FUNCTION LOAD REPLACE at every connect; Functions persist in the AOF, unlike the
-- EVALSHA script cache.
--
-- Rules every function keeps:
--  * ARGV[1] is the key prefix P; key names are computed here (one primary, no Cluster).
--  * Time is the server's (TIME), never a node's clock.
--  * Idempotent: a client timeout leaves the outcome unknown, so a repeat must be harmless.
--  * Replies are flat (hiredis 0.14 nests replies at most 9 levels) and use strings for
--    states, so the C++ side maps them to enums in one place.
--  * The work stream is never trimmed: acked entries are XDELed, so
--    XLEN - XPENDING = entries not yet delivered.
--
-- Keys under P: job:{id} (hash: state queued|running|assembling|done|failed|canceled, client,
-- prio, units, fed, done, created/started/finished_ms, ttl_ms, timeout_ms, opts, result, error,
-- assembler, local), tiles:{id} (hash unit -> result), client:{c} (hash: active), cjobs:{c}
-- (zset), queued/running/assembling (zsets by ms), deadlines (zset: running jobs with a limit,
-- by the ms they fail at), ring:{p} (list of clients with unfed units),
-- cj:{p}:{c} (list of that client's jobs with unfed units), work (stream, group 'render':
-- {job, unit, try}), idem:{#c}:{c}:{key} (string -> job id), node:{n} (string, PX),
-- nodes (zset),
-- lock:janitor; meta:build and meta:epoch are set by the client before the library loads.
-- Channels: P..'events' ("job state done total"), P..'cancel' (job ids).
local G = 'render'

local function now_ms()
  local t = redis.call('TIME')
  return tonumber(t[1]) * 1000 + math.floor(tonumber(t[2]) / 1000)
end

local function event(P, job, state, done, total)
  redis.call('PUBLISH', P .. 'events', job .. ' ' .. state .. ' ' .. done .. ' ' .. total)
end

local function is_active(state)
  return state == 'queued' or state == 'running' or state == 'assembling'
end

local function unlink_job_from_ring(P, prio, client, job)
  local jl = P .. 'cj:' .. prio .. ':' .. client
  redis.call('LREM', jl, 0, job)
  if redis.call('LLEN', jl) == 0 then redis.call('LREM', P .. 'ring:' .. prio, 0, client) end
end

-- Fields a caller may not set through finish/record's extra pairs.
local reserved = {state = true, client = true, prio = true, units = true, fed = true,
                  done = true, created_ms = true, started_ms = true, finished_ms = true,
                  ttl_ms = true, ['local'] = true, assembler = true, timeout_ms = true}

local function check_extra(a, from)
  if (#a - from + 1) % 2 ~= 0 then return 'ERR odd number of extra field arguments' end
  for i = from, #a, 2 do
    if reserved[a[i]] then return 'ERR field ' .. a[i] .. ' is set by the farm itself' end
  end
  return nil
end

-- Marks a job running from t: in the running index and, when it has a limit of its own
-- (its accepting node's --job-timeout), in the deadlines index the sweep reads.
local function start_running(P, job, t)
  local jk = P .. 'job:' .. job
  redis.call('HSET', jk, 'state', 'running', 'started_ms', t)
  redis.call('ZADD', P .. 'running', t, job)
  local limit = tonumber(redis.call('HGET', jk, 'timeout_ms') or '0') or 0
  if limit > 0 then redis.call('ZADD', P .. 'deadlines', t + limit, job) end
end

-- Moves an active job to a final state: out of the rings and indexes, tiles dropped, the
-- client's active count released, the record kept for its TTL, the event published.
local function end_job(P, job, state, err, extra, from)
  local jk = P .. 'job:' .. job
  local f = redis.call('HMGET', jk, 'client', 'prio', 'done', 'units', 'ttl_ms')
  local client, prio = f[1], f[2]
  redis.call('HSET', jk, 'state', state, 'finished_ms', now_ms())
  if err then redis.call('HSET', jk, 'error', err) end
  if extra then
    for i = from, #extra, 2 do redis.call('HSET', jk, extra[i], extra[i + 1]) end
  end
  unlink_job_from_ring(P, prio, client, job)
  redis.call('ZREM', P .. 'queued', job)
  redis.call('ZREM', P .. 'running', job)
  redis.call('ZREM', P .. 'deadlines', job)
  redis.call('ZREM', P .. 'assembling', job)
  redis.call('HINCRBY', P .. 'client:' .. client, 'active', -1)
  redis.call('UNLINK', P .. 'tiles:' .. job)
  local ttl = tonumber(f[5] or '0')
  if ttl > 0 then redis.call('PEXPIRE', jk, ttl) end
  event(P, job, state, f[3] or '0', f[4] or '0')
end

-- Tops the work stream up to `target` undelivered entries: strict priority, then round-robin
-- over clients, then over each client's jobs, one unit per turn (the local Scheduler's policy,
-- farm-wide). Each turn adds an entry or removes a finished job/client from a ring, so the
-- loop ends.
local function feed(P, target)
  local W = P .. 'work'
  local depth = redis.call('XLEN', W) - redis.call('XPENDING', W, G)[1]
  for prio = 0, 2 do
    local ring = P .. 'ring:' .. prio
    while depth < target do
      local client = redis.call('LMOVE', ring, ring, 'LEFT', 'RIGHT')
      if not client then break end
      local jl = P .. 'cj:' .. prio .. ':' .. client
      local job = redis.call('LMOVE', jl, jl, 'LEFT', 'RIGHT')
      if not job then
        redis.call('LREM', ring, 0, client)
      else
        local jk = P .. 'job:' .. job
        local f = redis.call('HMGET', jk, 'state', 'units', 'fed')
        local st, total, nxt = f[1], tonumber(f[2] or '0'), tonumber(f[3] or '0')
        if (st ~= 'queued' and st ~= 'running') or nxt >= total then
          unlink_job_from_ring(P, prio, client, job)
        else
          redis.call('XADD', W, '*', 'job', job, 'unit', nxt, 'try', 0)
          redis.call('HSET', jk, 'fed', nxt + 1)
          if st == 'queued' then
            local t = now_ms()
            redis.call('ZREM', P .. 'queued', job)
            start_running(P, job, t)
            event(P, job, 'running', 0, total)
          end
          if nxt + 1 >= total then unlink_job_from_ring(P, prio, client, job) end
          depth = depth + 1
        end
      end
    end
  end
end

-- An entry's fields as a table (entries are written only here: job, unit, try).
local function entry_fields(P, id)
  local r = redis.call('XRANGE', P .. 'work', id, id)
  if #r == 0 then return nil end
  local f = r[1][2]
  return {job = f[2], unit = f[4], try = tonumber(f[6])}
end

local function ack_delete(P, id)
  redis.call('XACK', P .. 'work', G, id)
  redis.call('XDEL', P .. 'work', id)
end

-- The unit is still wanted: its job is running and no result is stored for it.
local function wanted(P, job, unit)
  return redis.call('HGET', P .. 'job:' .. job, 'state') == 'running'
     and redis.call('HEXISTS', P .. 'tiles:' .. job, unit) == 0
end

-- Counts one more try of a unit that came back without a result: requeue it, or fail its job
-- once it has been tried max_tries times.
local function retry_or_fail(P, job, unit, try, max_tries, why)
  if try >= max_tries then
    end_job(P, job, 'failed', why)
    return 'failed'
  end
  redis.call('XADD', P .. 'work', '*', 'job', job, 'unit', unit, 'try', try)
  return 'requeued'
end

-- A client's jobs, newest kept: GET /jobs lists 100, and a term of submissions must not
-- grow Redis without end (the jobs themselves expire; their IDs here would not).
local client_jobs_kept = 1000
local function add_client_job(P, client, t, job)
  local k = P .. 'cjobs:' .. client
  redis.call('ZADD', k, t, job)
  redis.call('ZREMRANGEBYRANK', k, 0, -(client_jobs_kept + 1))
end

-- ARGV: P, job, client, prio, units, max_active, max_jobs, target, ttl_ms, idem_key,
--       idem_ttl_ms, opts, timeout_ms (0: none), field, value, ...
--   -> {'accepted'|'exists'|'limit'|'full', job}
-- units = 0: a local job, rendered by the accepting node (its field 'node') and ended with
-- rf1_record; it counts against the limits and is visible to every node, but is never fed.
local function submit(_, a)
  local P, job, client = a[1], a[2], a[3]
  local prio, units = tonumber(a[4]), tonumber(a[5])
  local max_active, max_jobs, target = tonumber(a[6]), tonumber(a[7]), tonumber(a[8])
  local ttl, idem, idem_ttl = tonumber(a[9]), a[10], tonumber(a[11])
  if prio ~= 0 and prio ~= 1 and prio ~= 2 then return redis.error_reply('ERR bad priority') end
  if not units or units < 0 then return redis.error_reply('ERR bad unit count') end
  local timeout = tonumber(a[13])
  if not timeout or timeout < 0 then return redis.error_reply('ERR bad timeout') end
  local bad = check_extra(a, 14)
  if bad then return redis.error_reply(bad) end
  local ik = nil
  if idem ~= '' then
    -- The client's length first: names may hold ':', and ("bob", "x:K") must not meet
    -- ("bob:x", "K"). A key whose job has expired is free again.
    ik = P .. 'idem:' .. #client .. ':' .. client .. ':' .. idem
    local prev = redis.call('GET', ik)
    if prev and redis.call('EXISTS', P .. 'job:' .. prev) == 1 then return {'exists', prev} end
  end
  local jk = P .. 'job:' .. job
  if redis.call('EXISTS', jk) == 1 then return {'exists', job} end
  local ck = P .. 'client:' .. client
  if tonumber(redis.call('HGET', ck, 'active') or '0') >= max_active then
    return {'limit', job}
  end
  if max_jobs > 0 and redis.call('ZCARD', P .. 'queued') + redis.call('ZCARD', P .. 'running')
      >= max_jobs then
    return {'full', job}
  end
  redis.call('HINCRBY', ck, 'active', 1)
  local t = now_ms()
  redis.call('HSET', jk, 'client', client, 'prio', prio, 'units', units, 'fed', 0,
             'done', 0, 'created_ms', t, 'ttl_ms', ttl, 'opts', a[12], 'timeout_ms', timeout)
  for i = 14, #a, 2 do redis.call('HSET', jk, a[i], a[i + 1]) end
  add_client_job(P, client, t, job)
  if ik then redis.call('SET', ik, job, 'PX', idem_ttl) end
  if units == 0 then
    redis.call('HSET', jk, 'local', '1')
    start_running(P, job, t)
    event(P, job, 'running', 0, 0)
    return {'accepted', job}
  end
  redis.call('HSET', jk, 'state', 'queued')
  redis.call('ZADD', P .. 'queued', t, job)
  -- Rings are rotated head to tail as they are served, so the head is the next turn: a client
  -- that joins goes next among the clients, and a new job takes its turn after its client's
  -- other jobs (so a client's jobs start in the order it sent them; each then gets one unit
  -- a turn, as in the local Scheduler).
  redis.call('RPUSH', P .. 'cj:' .. prio .. ':' .. client, job)
  if redis.call('LPOS', P .. 'ring:' .. prio, client) == false then
    redis.call('LPUSH', P .. 'ring:' .. prio, client)
  end
  event(P, job, 'queued', 0, units)
  -- Feeding here wakes nodes blocked on the stream.
  feed(P, target)
  return {'accepted', job}
end

-- Delivers entries to `node` until one is still wanted; stale ones are acked and deleted.
local function deliver(P, node, target)
  local W = P .. 'work'
  for _ = 1, 64 do
    local r = redis.call('XREADGROUP', 'GROUP', G, node, 'COUNT', 1, 'STREAMS', W, '>')
    if not r then return nil end
    local id, f = r[1][2][1][1], r[1][2][1][2]
    local job, unit = f[2], f[4]
    if wanted(P, job, unit) then
      return {id, job, unit, f[6], redis.call('HGET', P .. 'job:' .. job, 'opts')}
    end
    ack_delete(P, id)
    feed(P, target)
  end
  return nil
end

-- ARGV: P, node, target -> {entry, job, unit, try, opts} or nil
local function take(_, a)
  local P, node, target = a[1], a[2], tonumber(a[3])
  feed(P, target)
  local u = deliver(P, node, target)
  feed(P, target)
  return u
end

-- ARGV: P, node, target, entry -> {entry, job, unit, try, opts} or nil
-- For an entry the node got from its own XREADGROUP BLOCK (not allowed inside a Function):
-- the same checks as take; a stale entry is acked, deleted and the node handed the next one.
local function adopt(_, a)
  local P, node, target, id = a[1], a[2], tonumber(a[3]), a[4]
  local e = entry_fields(P, id)
  local u = nil
  if e and wanted(P, e.job, e.unit) then
    u = {id, e.job, e.unit, tostring(e.try), redis.call('HGET', P .. 'job:' .. e.job, 'opts')}
  else
    if e then ack_delete(P, id) end
    feed(P, target)
    u = deliver(P, node, target)
  end
  feed(P, target)
  return u
end

-- ARGV: P, node, ttl_ms, node_info, entry... -> entries whose lease was lost
-- XCLAIM by the owner with min-idle 0 and JUSTID resets the idle time without counting a
-- delivery: a lease renewal. Entries reclaimed meanwhile were deleted, so they are missing.
local function heartbeat(_, a)
  local P, node, ttl = a[1], a[2], tonumber(a[3])
  redis.call('SET', P .. 'node:' .. node, a[4], 'PX', ttl)
  redis.call('ZADD', P .. 'nodes', now_ms(), node)
  -- How long this node may go between renewals (its heartbeat's TTL): what the janitor must
  -- wait at least before it takes this node's units, whatever its own --lease-ms.
  redis.call('HSET', P .. 'renewal', node, ttl)
  if #a < 5 then return {} end
  local ids = {}
  for i = 5, #a do ids[#ids + 1] = a[i] end
  local kept = redis.call('XCLAIM', P .. 'work', G, node, 0, unpack(ids), 'JUSTID')
  local have = {}
  for _, id in ipairs(kept) do have[id] = true end
  local lost = {}
  for _, id in ipairs(ids) do if not have[id] then lost[#lost + 1] = id end end
  return lost
end

-- ARGV: P, node, entry, job, unit, payload -> 'ok'|'duplicate'|'drop'|'assemble'
-- The first result stored wins (rendering is deterministic, so any copy has the same bytes).
-- A repeat by the node that was told to assemble is told again.
local function complete(_, a)
  local P, node, id, job, unit = a[1], a[2], a[3], a[4], a[5]
  ack_delete(P, id)
  local jk = P .. 'job:' .. job
  local f = redis.call('HMGET', jk, 'state', 'units', 'assembler')
  local state, total = f[1], tonumber(f[2] or '0')
  local n = tonumber(unit)
  if not n or n < 0 or n >= total or n ~= math.floor(n) then
    if not state then return 'drop' end
    return redis.error_reply('ERR unit ' .. unit .. ' out of range for job ' .. job)
  end
  if state == 'assembling' and f[3] == node then return 'assemble' end
  if state ~= 'running' then return 'drop' end
  if redis.call('HSETNX', P .. 'tiles:' .. job, unit, a[6]) == 0 then return 'duplicate' end
  local done = redis.call('HINCRBY', jk, 'done', 1)
  if done >= total then
    local t = now_ms()
    redis.call('HSET', jk, 'state', 'assembling', 'assembler', node, 'assembling_ms', t)
    redis.call('ZREM', P .. 'running', job)
    redis.call('ZREM', P .. 'deadlines', job)  -- rendered: no longer the limit's to end
    redis.call('ZADD', P .. 'assembling', t, job)
    event(P, job, 'assembling', done, total)
    return 'assemble'
  end
  local t = now_ms()
  if t - tonumber(redis.call('HGET', jk, 'event_ms') or '0') >= 100 then
    redis.call('HSET', jk, 'event_ms', t)
    event(P, job, 'running', done, total)
  end
  return 'ok'
end

-- ARGV: P, node, entry, max_tries, error -> 'requeued'|'failed'|'drop'|'gone'
-- The node could not render the unit (an exception, out of memory, a scene error found late).
local function fail(_, a)
  local P, node, id, max_tries, err = a[1], a[2], a[3], tonumber(a[4]), a[5]
  local e = entry_fields(P, id)
  if not e then return 'gone' end
  ack_delete(P, id)
  if not wanted(P, e.job, e.unit) then return 'drop' end
  redis.call('HINCRBY', P .. 'job:' .. e.job, 'fail:' .. node, 1)
  redis.call('HSET', P .. 'job:' .. e.job, 'last_unit_error', err)
  local try = e.try + 1
  return retry_or_fail(P, e.job, e.unit, try, max_tries, 'unit ' .. e.unit .. ' failed ' ..
                       try .. ' times; the last time on ' .. node .. ': ' .. err)
end

-- ARGV: P, node, entry -> 'requeued'|'drop'|'gone'
-- Graceful drain: the unit goes back at once with the same try (7.0 has no XNACK).
local function release(_, a)
  local P, id = a[1], a[3]
  local e = entry_fields(P, id)
  if not e then return 'gone' end
  ack_delete(P, id)
  if not wanted(P, e.job, e.unit) then return 'drop' end
  redis.call('XADD', P .. 'work', '*', 'job', e.job, 'unit', e.unit, 'try', e.try)
  return 'requeued'
end

-- ARGV: P, janitor, lease_ms, max_tries, cursor, count -> {next_cursor, requeued, failed}
-- Entries idle past the lease belong to a node that died or stalled: requeue them with try+1
-- (so any idle node takes them at once), or fail the job once a unit was abandoned max_tries
-- times (a unit that kills every node it lands on must not crash-loop the farm). The lease is
-- the janitor's, or longer where a live node renews less often than that (nodes started
-- with other --heartbeat-ms than the janitor's: their units are not taken while they live).
local function reclaim(_, a)
  local P, jan, lease, max_tries = a[1], a[2], tonumber(a[3]), tonumber(a[4])
  local renewal = redis.call('HGETALL', P .. 'renewal')
  for i = 1, #renewal, 2 do
    if redis.call('EXISTS', P .. 'node:' .. renewal[i]) == 1 then
      lease = math.max(lease, tonumber(renewal[i + 1]) or 0)
    else
      redis.call('HDEL', P .. 'renewal', renewal[i])
      redis.call('ZREM', P .. 'nodes', renewal[i])  -- gone: no longer counted (rf1_counts)
    end
  end
  local r = redis.call('XAUTOCLAIM', P .. 'work', G, jan, lease, a[5], 'COUNT', a[6])
  local requeued, failed = 0, 0
  for _, e in ipairs(r[2]) do
    local id, f = e[1], e[2]
    ack_delete(P, id)
    if f and wanted(P, f[2], f[4]) then
      local try = tonumber(f[6]) + 1
      local why = 'unit ' .. f[4] .. ' was abandoned ' .. try ..
                  ' times: a node died or stalled on it each time'
      local res = retry_or_fail(P, f[2], f[4], try, max_tries, why)
      if res == 'failed' then failed = failed + 1 else requeued = requeued + 1 end
    end
  end
  return {r[1], requeued, failed}
end

-- ARGV: P, janitor, lease_ms, count -> {timed_out, orphaned, job to assemble, ...}
-- Jobs no unit lease covers: a job running past its deadline (its accepting node's limit)
-- fails (its units stop on the cancel channel); a local job whose node is gone fails; a job
-- whose assembler is gone (or has not finished in four leases) goes to the janitor, which
-- assembles it from the tiles (they are all in Redis).
local function sweep(_, a)
  local P, jan, lease, count = a[1], a[2], tonumber(a[3]), a[4]
  local t = now_ms()
  local timed_out, orphaned, assemble = 0, 0, {}
  local function node_alive(node)
    return node and redis.call('EXISTS', P .. 'node:' .. node) == 1
  end
  for _, job in ipairs(redis.call('ZRANGEBYSCORE', P .. 'deadlines', '-inf', t,
                                  'LIMIT', 0, count)) do
    local f = redis.call('HMGET', P .. 'job:' .. job, 'state', 'timeout_ms')
    local limit = tonumber(f[2] or '0') or 0
    redis.call('ZREM', P .. 'deadlines', job)
    -- (a job no longer running, or whose record expired, has nothing left to end)
    if f[1] == 'running' then
      end_job(P, job, 'failed', 'the job ran longer than its limit of ' ..
              string.format('%g', limit / 1000) .. ' s: lower spp, max_depth or the image size',
              {'code', 'timeout'}, 1)
      redis.call('PUBLISH', P .. 'cancel', job)
      timed_out = timed_out + 1
    end
  end
  for _, job in ipairs(redis.call('ZRANGEBYSCORE', P .. 'running', '-inf', t - lease,
                                  'LIMIT', 0, count)) do
    local f = redis.call('HMGET', P .. 'job:' .. job, 'local', 'node')
    if f[1] == '1' and not node_alive(f[2]) then
      end_job(P, job, 'failed', 'the node rendering it (' .. tostring(f[2] or '?') ..
              ') stopped; submit it again', {'code', 'node_lost'}, 1)
      orphaned = orphaned + 1
    end
  end
  for _, job in ipairs(redis.call('ZRANGEBYSCORE', P .. 'assembling', '-inf', t - lease,
                                  'LIMIT', 0, count)) do
    local jk = P .. 'job:' .. job
    local f = redis.call('HMGET', jk, 'assembler', 'assembling_ms')
    -- (an assembler alive but still at it after four leases failed to store the image)
    if not node_alive(f[1]) or tonumber(f[2] or '0') < t - 4 * lease then
      redis.call('HSET', jk, 'assembler', jan, 'assembling_ms', t)
      redis.call('ZADD', P .. 'assembling', t, job)
      assemble[#assemble + 1] = job
    end
  end
  local out = {timed_out, orphaned}
  for _, job in ipairs(assemble) do out[#out + 1] = job end
  return out
end

-- ARGV: P, job, client -> {'canceled'|'not_found'|'forbidden'|'already', state}
local function cancel(_, a)
  local P, job, client = a[1], a[2], a[3]
  local f = redis.call('HMGET', P .. 'job:' .. job, 'state', 'client')
  if not f[1] then return {'not_found', ''} end
  if f[2] ~= client then return {'forbidden', f[1]} end
  if not is_active(f[1]) then return {'already', f[1]} end
  end_job(P, job, 'canceled', nil)
  redis.call('PUBLISH', P .. 'cancel', job)
  return {'canceled', 'canceled'}
end

-- ARGV: P, node, job, result_key, field, value, ...
--   -> {'done'|'already_done'|'not_assembling', state}
-- Only from assembling: a canceled or failed job stays so.
local function finish(_, a)
  local P, job, result = a[1], a[3], a[4]
  local bad = check_extra(a, 5)
  if bad then return redis.error_reply(bad) end
  local f = redis.call('HMGET', P .. 'job:' .. job, 'state', 'result')
  if f[1] == 'done' and f[2] == result then return {'already_done', 'done'} end
  if f[1] ~= 'assembling' then return {'not_assembling', f[1] or ''} end
  redis.call('HSET', P .. 'job:' .. job, 'result', result)
  end_job(P, job, 'done', nil, a, 5)
  return {'done', 'done'}
end

-- ARGV: P, node, job, client, prio, state, ttl_ms, result, error, field, value, ...
--   -> {'recorded'|'exists'|'forbidden', state}
-- A job rendered on its node alone: ends the local job rf1_submit accepted (units = 0), or
-- writes a finished record for one that never went through submit.
local function record(_, a)
  local P, node, job, client, prio, state = a[1], a[2], a[3], a[4], a[5], a[6]
  local ttl, result, err = tonumber(a[7]), a[8], a[9]
  if state ~= 'done' and state ~= 'failed' and state ~= 'canceled' then
    return redis.error_reply('ERR record takes a final state, not ' .. state)
  end
  local bad = check_extra(a, 10)
  if bad then return redis.error_reply(bad) end
  local jk = P .. 'job:' .. job
  local f = redis.call('HMGET', jk, 'state', 'client', 'local')
  if f[1] then
    if f[2] ~= client then return {'forbidden', f[1]} end
    if not (f[1] == 'running' and f[3] == '1') then return {'exists', f[1]} end
    if result ~= '' then redis.call('HSET', jk, 'result', result) end
    redis.call('HSET', jk, 'node', node)
    end_job(P, job, state, err ~= '' and err or nil, a, 10)
    return {'recorded', state}
  end
  local t = now_ms()
  redis.call('HSET', jk, 'state', state, 'client', client, 'prio', prio, 'units', 0, 'fed', 0,
             'done', 0, 'created_ms', t, 'started_ms', t, 'finished_ms', t, 'ttl_ms', ttl,
             'local', '1', 'node', node)
  if result ~= '' then redis.call('HSET', jk, 'result', result) end
  if err ~= '' then redis.call('HSET', jk, 'error', err) end
  for i = 10, #a, 2 do redis.call('HSET', jk, a[i], a[i + 1]) end
  add_client_job(P, client, t, job)
  if ttl > 0 then redis.call('PEXPIRE', jk, ttl) end
  event(P, job, state, 0, 0)
  return {'recorded', state}
end

-- ARGV: P -> {queued, running, assembling, live nodes}: the farm's figures for /metrics and
-- /healthz. A node is live while its heartbeat key lasts.
local function counts(_, a)
  local P = a[1]
  local live = 0
  for _, node in ipairs(redis.call('ZRANGE', P .. 'nodes', 0, -1)) do
    live = live + redis.call('EXISTS', P .. 'node:' .. node)
  end
  return {redis.call('ZCARD', P .. 'queued'), redis.call('ZCARD', P .. 'running'),
          redis.call('ZCARD', P .. 'assembling'), live}
end

-- ARGV: P, node, ms -> 1 when `node` holds the janitor lock for the next ms (taken or renewed)
local function lock(_, a)
  local k = a[1] .. 'lock:janitor'
  if redis.call('SET', k, a[2], 'NX', 'PX', a[3]) then return 1 end
  if redis.call('GET', k) == a[2] then
    redis.call('PEXPIRE', k, a[3])
    return 1
  end
  return 0
end

-- ARGV: P, node, job, permille -> 1, or 0 when it is not a local job running on `node`
-- How far a job its accepting node renders alone has got, for every node's view of it.
local function progress(_, a)
  local jk = a[1] .. 'job:' .. a[3]
  local f = redis.call('HMGET', jk, 'state', 'local', 'node')
  if f[1] ~= 'running' or f[2] ~= '1' or f[3] ~= a[2] then return 0 end
  redis.call('HSET', jk, 'permille', a[4])
  return 1
end

-- Functions that free memory or keep leases alive still run when Redis is over maxmemory
-- (allow-oom); those that grow the data set (submit, take's feed, complete's tiles) get OOM.
local function reg(name, fn, flags)
  redis.register_function{function_name = name, callback = fn, flags = flags or {}}
end
reg('rf1_submit', submit)
reg('rf1_take', take)
reg('rf1_adopt', adopt)
reg('rf1_heartbeat', heartbeat, {'allow-oom'})
reg('rf1_complete', complete)
reg('rf1_fail', fail, {'allow-oom'})
reg('rf1_release', release, {'allow-oom'})
reg('rf1_reclaim', reclaim, {'allow-oom'})
reg('rf1_cancel', cancel, {'allow-oom'})
reg('rf1_sweep', sweep, {'allow-oom'})
reg('rf1_finish', finish, {'allow-oom'})
reg('rf1_record', record)
reg('rf1_lock', lock, {'allow-oom'})
reg('rf1_progress', progress)
reg('rf1_counts', counts, {'no-writes', 'allow-oom'})
