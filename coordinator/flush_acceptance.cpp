// A job's flushes, from the moment one arrives to the moment it counts (issue 44, part 1): one
// path for every upload, a single flush as a batch of one. In order: the job's phase (an ended
// job discards), the film (the right size, finite), each entry (its chain's next flush, sound
// counts), then, only when every entry is its chain's next flush, the batch made durable
// (coordinator/job_store.h: the worker hears "accepted" only for a flush on disk) and added to
// the sums once (coordinator/splat_aggregator.h); then each chain is answered (stop, yield or go
// on). The rest of the job is in job.cpp.
#include <set>

#include "coordinator/job.h"  // the class whose flushes these are
#include "coordinator/job_store.h"

namespace farm {

Status Job::acceptFlush(const std::string& worker, uint64_t epoch, ChainFlush&& flush,
                        SteadyClock::time_point now, FlushAck* ack, const EncodedSplats* wire) {
  // A single flush is a batch of one (acceptLocked); only its answer differs: what would refuse
  // an entry of a batch is the request's fault here, and says so in its status.
  const std::string name =
      "flush " + std::to_string(flush.flushIndex) + " of chain " + std::to_string(flush.chainIndex);
  FlushBatch batch = FlushBatch::of(std::move(flush), epoch);
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<FlushAck> acks;
  std::vector<FlushOutcome> outcomes;
  std::vector<std::string> problems;
  Status status =
      acceptLocked(worker, std::move(batch), name, now, &acks, &outcomes, &problems, wire);
  if (!status.isOk()) return status;
  *ack = acks.front();
  const std::string why = "job " + id_ + ": " + (outcomes.empty() ? "" : problems.front());
  switch (outcomes.empty() ? FlushOutcome::kAccepted : outcomes.front()) {
    case FlushOutcome::kOutOfOrder:
      return Status::failedPrecondition(why);
    case FlushOutcome::kUnknownChain:
      return Status::notFound(why);
    case FlushOutcome::kWrongSize:
    case FlushOutcome::kBadValues:
      return Status::invalidArgument(why);
    case FlushOutcome::kAccepted:
    case FlushOutcome::kDuplicate:
      break;
  }
  return Status::ok();
}

void Job::answerLocked(uint32_t chain, const std::string& worker, uint64_t epoch, bool accepted,
                       bool finished, int64_t mutations, FlushAck* ack) {
  const bool holder = scheduler_->holds(worker, chain, epoch);
  const bool chainEnds = finished && accepted;
  if (!chainEnds) {
    if (scheduler_->stopping()) {
      ack->stop = true;
      ack->reason = "the job's time budget is spent";
      if (holder) scheduler_->finishChain(chain);
    } else if (!holder) {
      ack->stop = true;
      ack->reason = "this worker no longer holds the lease of chain " + std::to_string(chain) +
                    " (it expired, moved to another worker, or the chain finished)";
    } else if (accepted && scheduler_->waitingCount() > 0 && mutations > 0 &&
               settings_.timeBudgetSeconds > 0) {
      // A chain without a budget would keep its thread until the time is up, and the others
      // would never run: time-slice them at flush boundaries (the chain resumes exactly).
      ack->stop = true;
      ack->reason = "chain " + std::to_string(chain) + " yields to waiting chains";
      ack->yielded = true;
      scheduler_->yieldChain(chain);
      if (workFreed_) workFreed_();
    }
  }
}

Status Job::acceptBatch(const std::string& worker, FlushBatch&& batch, SteadyClock::time_point now,
                        std::vector<FlushAck>* acks, const EncodedSplats* wire) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<FlushOutcome> outcomes;
  std::vector<std::string> problems;
  return acceptLocked(worker, std::move(batch), "the batch's film", now, acks, &outcomes, &problems,
                      wire);
}

Status Job::acceptLocked(const std::string& worker, FlushBatch&& batch, const std::string& filmName,
                         SteadyClock::time_point now, std::vector<FlushAck>* acks,
                         std::vector<FlushOutcome>* outcomes, std::vector<std::string>* problems,
                         const EncodedSplats* wire) {
  acks->assign(batch.entries.size(), FlushAck());
  outcomes->clear();
  problems->assign(batch.entries.size(), std::string());
  if (batch.entries.empty() || batch.epochs.size() != batch.entries.size()) {
    return Status::invalidArgument("a batch needs one lease epoch for each of its flushes");
  }
  if (isTerminal(phase_) || phase_ == JobPhase::kFinishing) {
    for (FlushAck& ack : *acks) {
      ack.result = FlushAck::Result::kDiscarded;
      ack.stop = true;
      ack.reason = std::string("job ") + id_ + " is " + jobPhaseName(phase_);
    }
    return Status::ok();
  }
  if (phase_ != JobPhase::kRendering) {
    return Status::failedPrecondition("job " + id_ + " is " + jobPhaseName(phase_) +
                                      "; it has no chains yet");
  }
  enforceBudgetLocked(now);
  std::set<uint32_t> chains;
  for (const ChainFlush& entry : batch.entries) {
    if (!chains.insert(entry.chainIndex).second) {
      return Status::invalidArgument("job " + id_ + ": the batch holds two flushes of chain " +
                                     std::to_string(entry.chainIndex));
    }
  }
  // The film is the batch's, not one chain's: when it is unsound, or sums chains of error
  // groups that must stay apart, every chain in it is charged.
  std::string problem;
  FlushOutcome film = aggregator_->checkGroups(batch, &problem);
  if (film == FlushOutcome::kAccepted)
    film = aggregator_->checkFilm(batch.film, filmName, &problem);
  if (film != FlushOutcome::kAccepted) {
    for (uint32_t chain : chains) {
      if (scheduler_->hasChain(chain)) countFailureLocked(worker, chain, problem);
    }
    return Status::invalidArgument("job " + id_ + ": " + problem);
  }
  // Each entry's verdict on its own; the batch counts only when every one is "the next flush".
  size_t next = 0;
  for (size_t i = 0; i < batch.entries.size(); ++i) {
    outcomes->push_back(aggregator_->checkEntry(batch.entries[i], &(*problems)[i]));
    next += (*outcomes)[i] == FlushOutcome::kAccepted;
  }
  const bool take = next == batch.entries.size();
  if (take) {
    if (store_) {
      // Durable before it counts: the worker hears "accepted" only for a flush on disk.
      Status recorded =
          store_->appendBatch(id_, batch, secondsSince(submitted_, now), &tailBytes_, wire);
      if (!recorded.isOk()) {
        log(recorded.message());
        return Status(StatusCode::kUnavailable,
                      "job " + id_ + ": the coordinator cannot record flushes now (send it again)");
      }
    }
    if (aggregator_->addBatch(batch, &problem) != FlushOutcome::kAccepted) {
      return Status::internal("job " + id_ + ": a checked batch did not add: " + problem);
    }
  }
  for (size_t i = 0; i < batch.entries.size(); ++i) {
    ChainFlush& entry = batch.entries[i];
    FlushAck& ack = (*acks)[i];
    switch ((*outcomes)[i]) {
      case FlushOutcome::kAccepted:
        if (take) {
          scheduler_->recordFlush(entry.chainIndex, entry.flushIndex, entry.mutations,
                                  std::move(entry.state), entry.finished, worker, batch.epochs[i],
                                  now);
          ack.result = FlushAck::Result::kAccepted;
        } else {
          ack.result = FlushAck::Result::kResend;  // sound, held back by another entry
        }
        break;
      case FlushOutcome::kDuplicate:
        ack.result = FlushAck::Result::kDuplicate;
        break;
      case FlushOutcome::kBadValues:
      case FlushOutcome::kWrongSize:
        countFailureLocked(worker, entry.chainIndex, (*problems)[i]);
        [[fallthrough]];
      case FlushOutcome::kOutOfOrder:
      case FlushOutcome::kUnknownChain:
        ack.result = FlushAck::Result::kRefused;
        ack.reason = (*problems)[i];
        break;
    }
    if (ack.result == FlushAck::Result::kAccepted || ack.result == FlushAck::Result::kDuplicate) {
      if (scheduler_->hasChain(entry.chainIndex)) {
        answerLocked(entry.chainIndex, worker, batch.epochs[i],
                     ack.result == FlushAck::Result::kAccepted, entry.finished, entry.mutations,
                     &ack);
      }
    }
  }
  if (take) {
    recordErrorLocked(now, false);
    checkpointLocked();
  }
  finishIfCompleteLocked(now);
  return Status::ok();
}

}  // namespace farm
