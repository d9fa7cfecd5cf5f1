@plc
Feature: The PLC side of the CAN interface
  The PLC writes new Tx messages only while Outputs.TxCounter equals
  Inputs.TxCounter, then sets Outputs.TxCounter to Inputs.TxCounter + 1; it
  reads NoOfRxMessages messages when Inputs.RxCounter changes and then sets
  Outputs.RxCounter to Inputs.RxCounter (000/001 §6, 003). Here the client is
  under test; the device, the EtherCAT master and the application are played
  by the harness, and every task is judged (rulings P1-P5).

  @base11 @CL-TX-001 @CL-TX-003 @CL-TX-004 @CL-TX-005
  Scenario: The device sends every message the application asked for, once and in order
    Given the client's interface is set up for 11-bit messages with 4 slots
    And the master is "lrw"
    When the application asks the client to send 10 messages
    And 3 cycles pass
    And the application asks the client to send 3 messages
    Then the client broke no requirement in any task
    And the bus carries every message the application asked for, once and in order

  @base11 @CL-TX-002
  Scenario: A batch stays as it is until the device has acknowledged it
    Given the client's interface is set up for 11-bit messages with 4 slots
    And the master is "lrw"
    When the application asks the client to send 1 message
    And 1 cycle passes
    And the application asks the client to send 6 messages
    Then the client broke no requirement in any task
    And the bus carries every message the application asked for, once and in order

  @base11 @CL-RX-001 @CL-RX-002 @CL-RX-003 @CL-RX-004
  Scenario: The client reads exactly NoOfRxMessages and copies Inputs.RxCounter
    Given the client's interface is set up for 11-bit messages with 4 slots
    And the master is "separate-input-update"
    When other nodes send 9 frames
    Then the client broke no requirement in any task
    And the application received every frame the other nodes sent, once and in order

  @base11 @CL-RST-001
  Scenario: After a PLC restart at most the batch in the image comes twice
    Given the client's interface is set up for 11-bit messages with 4 slots
    And the master is "lrw"
    When other nodes send 9 frames
    And the application asks the client to send 2 messages
    And 8 cycles pass
    And the PLC restarts
    And other nodes send 3 frames
    And the application asks the client to send 2 messages
    Then the client broke no requirement in any task
    And the application received every frame the other nodes sent, and at most 4 twice

  @base11 @CL-RST-002
  Scenario: After the device restarts the client exchanges frames again
    Given the client's interface is set up for 11-bit messages with 4 slots
    And the master is "lrw"
    When other nodes send 3 frames
    And 5 cycles pass
    And the device restarts
    And 1 cycle passes
    And other nodes send 3 frames
    And the application asks the client to send 2 messages
    Then the client broke no requirement in any task

  @base11 @CL-IMG-001
  Scenario: The client reads no more than the slots, whatever NoOfRxMessages says
    Given the client's interface is set up for 11-bit messages with 4 slots
    And the master is "lrw"
    When other nodes send 4 frames
    And the device reports NoOfRxMessages 65535 with its next batch
    Then the client broke no requirement in any task

  @fast_queue @base11 @CL-FQ-001
  Scenario: With the Fast CAN Queue every new RxCounter is read, nothing twice
    Given the client's interface is set up for 11-bit messages with 4 slots
    And the client's interface uses the Fast CAN Queue with 4 slots
    And the master is "lrw"
    When other nodes send 3 frames
    And 2 cycles pass
    And other nodes send 3 frames
    And 1 cycle passes
    And other nodes send 2 frames
    Then the client broke no requirement in any task
    And the application received every frame the other nodes sent, once and in order

  @base11 @CL-TX-002 @CL-RX-001
  Scenario Outline: The client does not rely on the buffer the master hands it
    Given the client's interface is set up for 11-bit messages with 4 slots
    And the master is "<master>"
    When the application asks the client to send 9 messages
    And other nodes send 9 frames
    Then the client broke no requirement in any task
    And the bus carries every message the application asked for, once and in order
    And the application received every frame the other nodes sent, once and in order

    Examples:
      | master              |
      | lrw-zeroed-outputs  |
      | lrw-triple-buffered |
      | lrw-overruns        |
      | half-cycle          |

  @ext29 @transaction_number @CL-TN-001
  Scenario: Transaction numbers tell the messages in flight apart
    Given the client's interface is set up for 29-bit messages with 4 slots
    And the master is "separate-input-update"
    When the application asks the client to send 12 messages
    Then the client broke no requirement in any task
    And the bus carries every message the application asked for, once and in order
