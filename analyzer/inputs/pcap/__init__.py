"""pcap / pcapng captures: file records, SocketCAN frames and the IDU link's TCP reassembly."""
